"""A frontier on a local Dask cluster against the same frontier in one process: the same errors for
the same settings, and what a point costs as a task.

    PYTHONPATH=build/python python3 examples/cluster_frontier.py OUT_DIR [--size N] [--spp N] [--preset P] [--workers W] [--from JSON]

Measures the preset's frontier (every method's accuracy knobs, mesolab.frontier) in this process
(every core) and then on W local workers of one thread each (mesolab.cluster.local_cluster, caches
of their own: the truth is spread in blocks first), each setting a task. Checks that every setting
measured by both has the same error (rmse_rel: the same truth's bytes, the same deterministic
frame), and writes OUT_DIR/cluster_frontier.png (both frontiers) and OUT_DIR/cluster_frontier.json
(the figures: wall times, the points' own work, what a point costs beyond it). With --from JSON it
draws the figure of a saved run instead of measuring.
"""
import argparse
import json
import os
import pathlib
import sys
import tempfile
import time

ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
ap.add_argument("out_dir")
ap.add_argument("--size", type=int, default=128, help="frame width and height")
ap.add_argument("--spp", type=int, default=64, help="the truth's samples per pixel")
ap.add_argument("--preset", default=str(pathlib.Path(__file__).resolve().parents[1] / "presets" / "microgeom" / "pom-bricks.json"))
ap.add_argument("--workers", type=int, default=2)
ap.add_argument("--from", dest="saved", help="a cluster_frontier.json of an earlier run: draw its figure, measure nothing")
args = ap.parse_args()
out = pathlib.Path(args.out_dir)
out.mkdir(parents=True, exist_ok=True)


def plot(figures, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 4.2), dpi=100)
    for run, colour, marker in (("one process", "#347", "o"), ("cluster", "#c63", "x")):
        r = figures[run]
        pts = r["points"]
        ax.scatter([p["frame_ms"] for p in pts], [p["rmse_rel"] for p in pts], s=14, c=colour, marker=marker, alpha=0.6,
                   label=f"{run}: {len(pts)} settings in {r['seconds']:.1f} s ({r['threads_per_point']} thread{'s' if r['threads_per_point'] > 1 else ''} a point)")
        front = sorted((p for p in pts if p["on_frontier"]), key=lambda p: p["frame_ms"])
        ax.step([p["frame_ms"] for p in front], [p["rmse_rel"] for p in front], where="post", c=colour, lw=1)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("frame time, stages cached (ms)")
    ax.set_ylabel("relative RMSE vs the truth")
    ax.set_title(f"{figures['scene']} at {figures['size'][0]}x{figures['size'][1]}: its frontier in one process and on {figures['workers']} local workers\n"
                 f"a point costs {figures['per_point_s'] * 1e3:.0f} ms beyond its own work on a worker; same error for every setting both measured",
                 fontsize=8)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path)


if args.saved:
    plot(json.loads(pathlib.Path(args.saved).read_text()), out / "cluster_frontier.png")
    sys.exit(0)

work = pathlib.Path(tempfile.mkdtemp(prefix="mesolab-cluster-"))
os.environ["MESOLAB_CACHE_DIR"] = str(work / "cache")  # this process's truths: none cached from before

import mesolab  # noqa: E402

scene = mesolab.load_preset(args.preset)
options = dict(size=(args.size, args.size), spp=args.spp, budget=3600, repeat=3)
os.environ["MESOLAB_CACHE_DIR"] = str(work / "one-process-cache")  # its truth apart: the cluster would continue it, not render it
t0 = time.perf_counter()
one = mesolab.frontier(scene, **options)
one_s = time.perf_counter() - t0
os.environ["MESOLAB_CACHE_DIR"] = str(work / "cache")

with mesolab.cluster.local_cluster(args.workers, threads=1, folder=work) as client:
    started = {}

    def progress(stage, fraction):  # the points start once the truth is spread
        if stage.startswith("frontier of"):
            started.setdefault("points", time.perf_counter())

    t0 = time.perf_counter()
    spread = mesolab.frontier(scene, client=client, progress=progress, **options)
    cluster_s = time.perf_counter() - t0
    truth_s = started["points"] - t0

key = lambda p: (p["distance"], p["method"], tuple(p["knobs"].items()))
errors = {key(p): p["rmse_rel"] for p in one}
both = [p for p in spread if key(p) in errors]
assert both and all(p["rmse_rel"] == errors[key(p)] for p in both), "a setting's error differs between the cluster and this process"


def work_s(points):  # each point's own measured work: its precomputation and its four frames (the first and `repeat`)
    return sum(p["precompute_ms"] + (1 + options["repeat"]) * p["frame_ms"] for p in points) / 1e3


per_worker = work_s(spread) / args.workers
figures = {
    "preset": args.preset, "scene": scene.name, "size": options["size"], "spp": args.spp, "workers": args.workers, "cpu_threads": os.cpu_count(),
    "one process": {"seconds": one_s, "points": one, "work_s": work_s(one), "threads_per_point": os.cpu_count()},
    "cluster": {"seconds": cluster_s, "truth_s": truth_s, "points": spread, "work_s": work_s(spread), "threads_per_point": 1,
                "budget_reached": mesolab.cluster.last_run["budget_reached"]},
    "same_error_settings": len(both),
    # Beyond the points' own work, per point on a worker: the task's round trips, each distinct truth read once per worker.
    "per_point_s": max(0.0, (cluster_s - truth_s - per_worker) / (len(spread) / args.workers)),
}
(out / "cluster_frontier.json").write_text(json.dumps(figures, indent=1) + "\n")
plot(figures, out / "cluster_frontier.png")
print(json.dumps({k: v for k, v in figures.items() if k not in ("one process", "cluster")}, indent=2))
print(f"one process {one_s:.1f} s ({len(one)} settings); cluster {cluster_s:.1f} s ({len(spread)} settings, truth {truth_s:.1f} s)")
