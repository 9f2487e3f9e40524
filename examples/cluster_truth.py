"""A truth on a local Dask cluster against the same truth in one process: the same bytes, and what
the cluster costs.

    PYTHONPATH=build/python python3 examples/cluster_truth.py OUT_DIR [--size N] [--spp N] [--preset P] [--workers W] [--from JSON]

Starts a `dask scheduler` and W `dask worker` processes on 127.0.0.1 (one thread each, MESOLAB_THREADS=1,
caches of their own), renders the preset's truth in this process (every core) and then on the cluster
twice: cold (the pack sent and unpacked, each worker's Workbench and stages made) and warm (another
seed: nothing reused but the workers); then once more in blocks of 4 samples, to measure what a task
costs beyond its samples. Checks that the cluster's truth is this process's bytes, and writes
OUT_DIR/cluster_truth.png (the times as bars) and OUT_DIR/cluster_truth.json (the figures). With
--from JSON it draws the figure of a saved run instead of measuring.
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
ap.add_argument("--size", type=int, default=256, help="frame width and height")
ap.add_argument("--spp", type=int, default=64)
ap.add_argument("--preset", default=str(pathlib.Path(__file__).resolve().parents[1] / "presets" / "basic" / "torus-sky.json"))
ap.add_argument("--workers", type=int, default=2)
ap.add_argument("--from", dest="saved", help="a cluster_truth.json of an earlier run: draw its figure, measure nothing")
args = ap.parse_args()
out = pathlib.Path(args.out_dir)
out.mkdir(parents=True, exist_ok=True)


def plot(figures, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    one_s = figures["one_process_s"]
    labels = ["one process"] + [f"cluster, {k}" for k in figures["cluster"]]
    secs = [one_s] + [v["seconds"] for v in figures["cluster"].values()]
    fig, ax = plt.subplots(figsize=(7, 3.4), dpi=100)
    bars = ax.barh(labels[::-1], secs[::-1], color=["#888"] * len(figures["cluster"]) + ["#347"])
    for b, s in zip(bars, secs[::-1]):
        ax.text(b.get_width(), b.get_y() + b.get_height() / 2, f" {s:.2f} s ({s / one_s - 1:+.0%})", va="center", fontsize=8)
    ax.set_xlabel("seconds to a truth of %d spp at %dx%d" % (figures["spp"], *figures["size"]))
    ax.set_title(f"{figures['scene']}: {figures['workers']} local workers (1 thread each) against one process ({figures['cpu_threads']} threads)\n"
                 f"a task costs {figures['per_task_s'] * 1e3:.0f} ms beyond its samples", fontsize=9)
    ax.set_xlim(0, max(secs) * 1.35)
    fig.tight_layout()
    fig.savefig(path)


if args.saved:
    plot(json.loads(pathlib.Path(args.saved).read_text()), out / "cluster_truth.png")
    sys.exit(0)

work = pathlib.Path(tempfile.mkdtemp(prefix="mesolab-cluster-"))
os.environ["MESOLAB_CACHE_DIR"] = str(work / "cache")  # this process's truths: none cached from before

import mesolab  # noqa: E402

with mesolab.cluster.local_cluster(args.workers, threads=1, folder=work) as client:  # caches of their own
    scene = mesolab.load_preset(args.preset)
    size = (args.size, args.size)
    os.environ["MESOLAB_CACHE_DIR"] = str(work / "one-process-cache")  # this process's truth apart: the cluster would continue it
    wb = mesolab.Workbench()
    os.environ["MESOLAB_CACHE_DIR"] = str(work / "cache")
    wb.render(scene, backend="cpu", size=(16, 16))  # this process's own warm-up (stages), outside the clock, as the workers' is not
    t0 = time.perf_counter()
    one = wb.render(scene, backend="truth", size=size, spp=args.spp, seed=1, aovs=["truth_stderr", "normal"])
    one_s = time.perf_counter() - t0

    runs = {}
    for name, seed, block in (("cold", 1, None), ("warm", 2, None), ("blocks of 4", 3, 4)):
        with mesolab.Workbench() as other:
            t0 = time.perf_counter()
            frame = other.render(scene, client=client, backend="truth", size=size, spp=args.spp, seed=seed, block=block)
            runs[name] = dict(seconds=time.perf_counter() - t0, **mesolab.cluster.last_run)
        if name == "cold":
            same = all(one[a].tobytes() == frame[a].tobytes() for a in ("radiance", "truth_stderr", "normal"))
            assert same, "the cluster's truth differs from this process's"

# What a task costs beyond its samples: the warm run's tasks against the blocks of 4 (same samples, many more tasks).
warm, small = runs["warm"]["tasks"], runs["blocks of 4"]["tasks"]
per_task_s = (sum(t["seconds"] for t in small) - sum(t["seconds"] for t in warm)) / max(1, len(small) - len(warm))
figures = {
    "preset": args.preset, "scene": scene.name, "size": size, "spp": args.spp, "workers": args.workers, "cpu_threads": os.cpu_count(),
    "one_process_s": one_s,
    "cluster": {k: {"seconds": v["seconds"], "tasks": len(v["tasks"]), "overhead": v["seconds"] / one_s - 1.0,
                    "task_seconds": sum(t["seconds"] for t in v["tasks"]), "merge_s": v["merge_s"], "pack_bytes": v["pack_bytes"]}
                for k, v in runs.items()},
    "per_task_s": per_task_s,
    "same_bytes": True,
}
(out / "cluster_truth.json").write_text(json.dumps(figures, indent=2) + "\n")

plot(figures, out / "cluster_truth.png")
print(json.dumps(figures, indent=2))
