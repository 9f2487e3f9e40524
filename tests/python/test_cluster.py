# mesolab on a real Dask.distributed cluster on 127.0.0.1: a `dask scheduler` and two `dask worker`
# processes (one thread each, MESOLAB_THREADS=1, a cache folder of their own), started here and
# stopped at the end. Truths merged from blocks on any worker are the one-process bytes, a worker
# that dies has its task rerun, packs carry arrays, Ctrl-C stops the workers, OpenGL is a resource.
import _thread
import os
import signal
import subprocess
import sys
import threading
import time
import types

import distributed  # python3-distributed: part of the project's packages, so no skip
import numpy as np
import pytest

from conftest import PRESETS

SIZE = (40, 32)
DIE_SEED, DIE_FIRST = 77, 8


def _start(args, env, log):
    return subprocess.Popen([sys.executable, "-m", "dask", *args], env=env, stdout=log, stderr=subprocess.STDOUT, start_new_session=True)


@pytest.fixture(scope="module")
def cluster(tmp_path_factory, mesolab):
    d = tmp_path_factory.mktemp("dask")
    env = {"DASK_DISTRIBUTED__WORKER__DAEMON": "False", "MESOLAB_TEST_EXIT_ONCE": f"{d / 'died'}:{DIE_SEED}:{DIE_FIRST}"}
    with mesolab.cluster.local_cluster(2, threads=1, folder=d, env=env) as client:  # `dask scheduler` and `dask worker` processes
        yield types.SimpleNamespace(client=client, dir=d)


@pytest.fixture(scope="module", autouse=True)
def caller_cache(tmp_path_factory):
    """This process's truth cache, fresh for the module: the cluster continues what it holds, so only what these tests put there."""
    old = os.environ.get("MESOLAB_CACHE_DIR")
    os.environ["MESOLAB_CACHE_DIR"] = str(tmp_path_factory.mktemp("caller-cache"))
    yield
    if old is None:
        os.environ.pop("MESOLAB_CACHE_DIR")
    else:
        os.environ["MESOLAB_CACHE_DIR"] = old


@pytest.fixture(scope="module")
def ref(mesolab, tmp_path_factory, caller_cache):
    """The one-process references: a workbench with a truth cache of its own, so that they are rendered here (not read from what
    the cluster merged) and the cluster does not continue them."""
    old = os.environ["MESOLAB_CACHE_DIR"]
    os.environ["MESOLAB_CACHE_DIR"] = str(tmp_path_factory.mktemp("reference-cache"))
    try:
        w = mesolab.Workbench()  # its truth cache is where MESOLAB_CACHE_DIR points now
    finally:
        os.environ["MESOLAB_CACHE_DIR"] = old
    yield w
    w.close()


def _sphere(mesolab):
    return mesolab.load_preset(PRESETS / "basic" / "sphere.json")


def _same(a, b):
    for aov in ("radiance", "truth_stderr", "normal"):
        assert a[aov].tobytes() == b[aov].tobytes(), aov


def test_a_truth_from_blocks_on_two_workers_is_the_one_process_truth(mesolab, cluster, ref):
    scene = _sphere(mesolab)
    one = ref.render(scene, backend="truth", size=SIZE, spp=24, seed=5, aovs=["truth_stderr", "normal"])
    seen = []
    with mesolab.Workbench() as other:
        spread = other.render(scene, client=cluster.client, backend="truth", size=SIZE, spp=24, seed=5, block=4,
                              progress=lambda stage, f: seen.append(f))
    _same(one, spread)
    run = mesolab.cluster.last_run
    assert sorted((t["first"], t["end"]) for t in run["tasks"]) == [(a, a + 4) for a in range(0, 24, 4)]
    assert len({t["worker"] for t in run["tasks"]}) == 2, "both workers should take blocks"
    assert seen[0] == 0 and seen[-1] == 1 and seen == sorted(seen), "progress reaches the caller, block by block"
    # Blocks merge to the same bytes in any order (exact integer sums).
    parts = [(f"{a}:{a + 8}", ref._truth_part(scene, SIZE, 5, a, a + 8)) for a in (0, 8, 16)]
    forward = mesolab._core._merge_truth_parts(parts)
    assert mesolab._core._merge_truth_parts(parts[::-1]) == forward
    assert mesolab._core._merge_truth_parts([parts[1], parts[2], parts[0]]) == forward
    with mesolab.Workbench() as third:
        _same(one, third._truth_from_part(scene, forward))
        # This process's truth cache now holds those 24 samples (as if rendered here): asked again, no task; asked for 36, the
        # cluster continues them with samples [24, 36) alone, to the one-process bytes of 36.
        again = third.render(scene, client=cluster.client, backend="truth", size=SIZE, spp=24, seed=5)
        assert mesolab.cluster.last_run == {"tasks": [], "cached_spp": 24}
        _same(one, again)
        more = third.render(scene, client=cluster.client, backend="truth", size=SIZE, spp=36, seed=5, block=4)
        run = mesolab.cluster.last_run
        assert run["cached_spp"] == 24 and sorted((t["first"], t["end"]) for t in run["tasks"]) == [(24, 28), (28, 32), (32, 36)]
        _same(ref.render(scene, backend="truth", size=SIZE, spp=36, seed=5, aovs=["truth_stderr", "normal"]), more)


def test_a_worker_that_dies_has_its_block_rerun_and_the_bytes_hold(mesolab, cluster, ref):
    scene = _sphere(mesolab)
    one = ref.render(scene, backend="truth", size=SIZE, spp=16, seed=DIE_SEED, aovs=["truth_stderr", "normal"])
    spread = mesolab.Workbench().render(scene, client=cluster.client, backend="truth", size=SIZE, spp=16, seed=DIE_SEED, block=4)
    assert (cluster.dir / "died").exists(), "the test hook should have ended a worker process"
    _same(one, spread)
    cluster.client.wait_for_workers(2, timeout=90)  # the nanny restarts it


def test_packs_carry_what_the_scene_names_even_arrays(mesolab, cluster, ref):
    scene = _sphere(mesolab)
    rng = np.random.default_rng(3)
    scene["basic.albedo_map"] = (rng.random((16, 16, 3)) * 255).astype(np.uint8)  # in this process's cache only
    one = ref.render(scene, backend="truth", size=SIZE, spp=8, seed=9, aovs=["truth_stderr", "normal"])
    spread = mesolab.Workbench().render(scene, client=cluster.client, backend="truth", size=SIZE, spp=8, seed=9)
    _same(one, spread)
    assert mesolab.cluster.last_run["pack_bytes"] > 16 * 16 * 3 // 4


def test_ctrl_c_cancels_the_queue_and_stops_running_tasks(mesolab, cluster):
    scene = _sphere(mesolab)
    timer = threading.Timer(3.0, _thread.interrupt_main)
    timer.start()
    t0 = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        mesolab.Workbench().render(scene, client=cluster.client, backend="truth", size=(64, 64), spp=400000, seed=2, block=100000)
    timer.cancel()
    assert time.monotonic() - t0 < 30
    deadline = time.monotonic() + 20
    while any(cluster.client.processing().values()):
        assert time.monotonic() < deadline, f"tasks still running 20 s after Ctrl-C: {cluster.client.processing()}"
        time.sleep(0.2)
    assert len(cluster.client.nthreads()) == 2, "the workers survive a cancel"
    # A frontier's points too (Ctrl-C once its first point is in): its queued settings are cancelled, the running ones stop at
    # their next poll.
    def interrupt_after_the_first_point(stage, fraction):
        if stage.startswith("frontier of") and fraction > 0:
            _thread.interrupt_main()

    with pytest.raises(KeyboardInterrupt):
        mesolab.frontier(scene, client=cluster.client, size=(512, 512), spp=4, repeat=100, budget=600, progress=interrupt_after_the_first_point)
    deadline = time.monotonic() + 20
    while any(cluster.client.processing().values()):
        assert time.monotonic() < deadline, f"frontier tasks still running 20 s after Ctrl-C: {cluster.client.processing()}"
        time.sleep(0.2)


def test_a_mixed_cluster_is_refused(mesolab, ref):
    scene = _sphere(mesolab)
    build = mesolab._core._truth_build().encode()
    other = build[:-1] + (b"X" if build[-1:] != b"X" else b"Y")
    a = ref._truth_part(scene, SIZE, 5, 0, 4)
    b = ref._truth_part(scene, SIZE, 5, 4, 8).replace(build, other)
    with pytest.raises(mesolab.InputError, match="build"):
        mesolab._core._merge_truth_parts([("a", a), ("b", b)])
    with pytest.raises(mesolab.InputError, match="another build"):
        ref._truth_from_part(scene, mesolab._core._merge_truth_parts([("a", a.replace(build, other))]))
    with pytest.raises(mesolab.InputError, match="worker tcp://10.0.0.9:1 renders with another build"):
        mesolab.cluster._one_build([("tcp://10.0.0.9:1", other.decode())])


def test_gl_work_needs_a_gl_worker(mesolab, cluster):
    scene = _sphere(mesolab)
    with pytest.raises(mesolab.InputError, match="resource GL"):
        mesolab.sweep(scene, client=cluster.client, knob="geometry.resolution", values=[8, 16], backend="gpu")
    with pytest.raises(mesolab.InputError, match="resource GL"):
        mesolab.bench("basic", client=cluster.client, backend="both")
    with pytest.raises(mesolab.InputError, match="resource GL"):
        mesolab.frontier(scene, client=cluster.client, backend="gpu")
    # A worker that declares GL takes the GL work, and only it.
    env = dict(os.environ, MESOLAB_THREADS="1", PYTHONDONTWRITEBYTECODE="1", MESOLAB_CACHE_DIR=str(cluster.dir / "gl-cache"))
    with open(cluster.dir / "gl.log", "w") as log:
        gl = _start(["worker", "--scheduler-file", str(cluster.dir / "scheduler.json"), "--nthreads", "1", "--no-dashboard", "--memory-limit", "0",
                     "--name", "gl", "--resources", "GL=1", "--local-directory", str(cluster.dir / "gl")], env, log)
        try:
            cluster.client.wait_for_workers(3, timeout=90)
            address = [a for a, w in cluster.client.scheduler_info()["workers"].items() if w.get("name") == "gl"][0]
            points = mesolab.sweep(scene, client=cluster.client, knob="geometry.resolution", values=[8, 16, 32], size=(24, 24), repeat=1, backend="gpu")
            assert {p["worker"] for p in points} == {address}
            assert points[0]["error"] > points[-1]["error"] > 0  # against the declared reference resolution
            cluster.client.retire_workers([address], close_workers=True)
        finally:
            try:
                os.killpg(gl.pid, signal.SIGTERM)
            except ProcessLookupError:
                pass
            gl.wait(timeout=30)
    deadline = time.monotonic() + 30
    while len(cluster.client.nthreads()) != 2:
        assert time.monotonic() < deadline
        time.sleep(0.2)


def test_a_truth_to_a_noise_target_on_the_cluster_is_the_one_process_truth_of_its_samples(mesolab, cluster, ref):
    scene = _sphere(mesolab)
    seen = []
    with mesolab.Workbench() as other:
        spread = other.render(scene, client=cluster.client, backend="truth", size=SIZE, noise=0.01, seed=9, aovs=["truth_stderr", "normal"],
                              progress=lambda stage, f: seen.append((stage, f)))
        rounds = mesolab.cluster.last_run["rounds"]
        t = spread.truth
        assert t["ended"] == "noise" and t["noise_target"] == 0.01 and t["noise_rel"] <= 0.01
        assert len(rounds) >= 2 and rounds[-1]["end"] == t["spp"]  # a first round of 16 samples was not enough
        assert rounds[-1]["noise_rel"] <= 0.01 < min(r["noise_rel"] for r in rounds[:-1])
        assert seen[-1][1] == 1.0 and "target 1.00%" in seen[-1][0]
        _same(ref.render(scene, backend="truth", size=SIZE, spp=t["spp"], seed=9, aovs=["truth_stderr", "normal"]), spread)
        # The most samples (spp=) and a time limit end it too, each said.
        capped = other.render(scene, client=cluster.client, backend="truth", size=SIZE, noise=1e-4, spp=40, seed=9)
        assert (capped.truth["ended"], capped.truth["spp"]) == ("samples", 40)
        timed = other.render(scene, client=cluster.client, backend="truth", size=SIZE, noise=1e-4, time_limit=1.5, seed=9)
        assert timed.truth["ended"] == "time limit" and timed.truth["noise_rel"] > 1e-4
        with pytest.raises(mesolab.InputError, match="noise"):
            other.render(scene, client=cluster.client, backend="truth", size=SIZE, noise=-1)


def test_a_sweep_spread_over_points_measures_what_one_process_does(mesolab, cluster):
    scene = _sphere(mesolab)
    values = [6, 12, 24]
    for metric, extra in (("rmse", {}), ("truth", {"spp": 8})):
        local = mesolab.sweep(scene, knob="geometry.resolution", values=values, size=(24, 24), repeat=1, metric=metric, **extra)
        spread = mesolab.sweep(scene, client=cluster.client, knob="geometry.resolution", values=values, size=(24, 24), repeat=1, metric=metric, **extra)
        assert [p["value"] for p in spread] == values
        assert [p["error"] for p in spread] == [p["error"] for p in local], metric
        assert all(p["ms"] > 0 for p in spread)
    # The truth to a noise target (sampled in rounds on the cluster): the one process's errors against the truth of as many samples.
    aimed = mesolab.sweep(scene, client=cluster.client, knob="geometry.resolution", values=values, size=(24, 24), repeat=1, metric="truth", noise=0.02)
    n = aimed[0]["truth_spp"]
    assert n > 16 and all(p["truth_spp"] == n for p in aimed)
    local = mesolab.sweep(scene, knob="geometry.resolution", values=values, size=(24, 24), repeat=1, metric="truth", spp=n)
    assert [p["error"] for p in aimed] == [p["error"] for p in local]
    # A worker's tasks run on its process's kept Workbench (_on=): a sweep there leaves its last setting's stages in that
    # workbench's cache and measures what a sweep of its own does.
    with mesolab.Workbench() as kept:
        assert kept.cache_entries == 0
        on = mesolab._core.sweep(scene, knob="geometry.resolution", values=values, size=(24, 24), repeat=1, _on=kept)
        assert kept.cache_entries > 0
        own = mesolab.sweep(scene, knob="geometry.resolution", values=values, size=(24, 24), repeat=1)
        assert [p["error"] for p in on] == [p["error"] for p in own]
        cells = mesolab._core.bench("basic", backend="cpu", repeat=1, rows=[mesolab._core._bench_rows("basic")[0][1]], columns=["frame 512"], _on=kept)
        assert cells and all(c["median_ms"] > 0 for c in cells if "median_ms" in c)


def test_a_frontier_spread_over_its_points_measures_what_one_process_does(mesolab, cluster, tmp_path):
    import json
    scene = _sphere(mesolab)
    kw = dict(size=(24, 24), spp=8, repeat=1)
    local = mesolab.frontier(scene, distances=[3.0], budget=600, **kw)
    seen = []
    spread = mesolab.frontier(scene, client=cluster.client, distances=[3.0], budget=600, progress=lambda stage, f: seen.append(f) if stage.startswith("frontier") else None,
                              **kw)
    assert seen[-1] == 1.0 and all(a <= b for a, b in zip(seen, seen[1:]))
    assert len({p["worker"] for p in spread}) == 2  # one distance's settings on both workers
    # The first round: the one-process frontier's settings in its order, with its errors exactly (the same truth's bytes).
    first = mesolab._core._frontier_settings(scene, dict(size=(24, 24), distances=[3.0], spp=8, repeat=1))
    n = len(first)
    assert n >= 4
    name = lambda p: (p["method"], p["setting"], tuple(p["knobs"].items()))
    assert [name(p) for p in spread[:n]] == [name(s) for s in first]
    one = {name(p): p["rmse_rel"] for p in local}
    assert [p["rmse_rel"] for p in spread[:n]] == [one[name(p)] for p in spread[:n]]
    # The second round: between the first round's frontier, as the one process chooses them from these points.
    # (Which points are on it depends on the frame times: on a loaded machine there may be no neighbours to go between.)
    between = mesolab._core._frontier_between(scene, spread[:n])
    assert [name(p) for p in spread[n:]] == [name(s) for s in between]
    # The rounds' choice itself, from points made up: error falling as time grows puts every point on the frontier, and
    # the second round goes between each two neighbours at the geometric mean of their resolutions.
    made_up = [dict(p, distance=3.0, precompute_ms=0.0, frame_ms=float(p["knobs"]["geometry.resolution"]), rmse_rel=1.0 / float(p["knobs"]["geometry.resolution"]),
                    below_noise=False) for p in first]
    between = mesolab._core._frontier_between(scene, made_up)
    assert [b["knobs"]["geometry.resolution"] for b in between] == ["34", "68", "136", "272"]
    assert between[0]["setting"] == "between all x0.25 and all x0.5"
    assert min(spread, key=lambda p: (p["frame_ms"], p["rmse_rel"]))["on_frontier"]  # the frontier marked: its fastest point is on it
    # Two distances at once, with the files; then a budget of 0: each method's preset at each distance, the rest left out and said.
    both = mesolab.frontier(scene, client=cluster.client, distances=[3.0, 5.0], budget=600, out_dir=tmp_path / "f", **kw)
    assert {p["distance"] for p in both} == {3.0, 5.0}
    written = json.loads((tmp_path / "f" / f"{scene.name}.frontier.json").read_text())
    assert len(written["points"]) == len(both) and "worker" in written["machine"]
    assert (tmp_path / "f" / f"{scene.name}.frontier.d5.png").exists()
    # A setting's task after the budget has ended is left out, a preset's measured all the same.
    from distributed import Event
    Event("mesolab-budget-test", client=cluster.client).set()
    options = dict(size=(24, 24), distances=[3.0], spp=8, repeat=1)
    for setting, measured in ((first[1], False), (first[0], True)):
        pack = mesolab._core._pack_bytes(scene)
        r = cluster.client.submit(mesolab.cluster._frontier_point_task, pack, mesolab._core._content_hash(pack), options, 3.0, setting,
                                  "mesolab-cancel-test", "mesolab-budget-test", pure=False).result()
        assert (r["point"] is not None, r["stopped"]) == (measured, not measured)
    # Truths to a noise target: each distance's truth sampled in rounds, its points measured against it (the one process's
    # errors against the truth of as many samples).
    aimed = mesolab.frontier(scene, client=cluster.client, distances=[3.0], budget=0, size=(24, 24), noise=0.02, repeat=1)
    n = mesolab.cluster.last_run["truth_spp"][0]
    assert n > 16 and mesolab.cluster.last_run["budget_reached"]
    assert [p["rmse_rel"] for p in aimed] == [p["rmse_rel"] for p in mesolab.frontier(scene, distances=[3.0], budget=0, size=(24, 24), spp=n, repeat=1)]
    only = mesolab.frontier(scene, client=cluster.client, distances=[3.0, 5.0], budget=0, **kw)
    assert sorted((p["distance"], p["setting"]) for p in only) == [(3.0, "preset"), (5.0, "preset")]
    assert mesolab.cluster.last_run["budget_reached"]
    assert "The budget ended the run" in mesolab.cluster.last_run["markdown"]


def test_a_bench_spread_over_rows(mesolab, cluster):
    scene = _sphere(mesolab)
    rows = [r for t, r in mesolab._core._bench_rows("basic")][:2]
    cells = mesolab.bench("basic", client=cluster.client, backend="cpu", repeat=1, rows=rows, columns=["frame 512"])
    assert {c["row"] for c in cells} >= set(rows)
    assert all(c["median_ms"] > 0 for c in cells if "median_ms" in c)
    # A user's scene as a truth row, sent as a pack to the worker that measures it.
    tiny = _sphere(mesolab)
    tiny["geometry.resolution"] = 12
    tiny.save(cluster.dir / "tiny.zip")
    cells = mesolab.bench("truth", client=cluster.client, presets=[cluster.dir / "tiny.zip"], backend="cpu", repeat=1)
    assert cells and {c["row"] for c in cells} == {tiny.name}
    with pytest.raises(mesolab.InputError, match="out_dir"):
        mesolab.sweep(scene, client=cluster.client, knob="geometry.resolution", values=[8], out_dir="x")


def test_the_slurm_job_array_script_spreads_a_truth_that_truth_merge_joins(mesolab, tmp_path):
    from conftest import BINARY, ROOT, cli
    cli("preset", "pack", PRESETS / "basic" / "sphere.json", "-o", tmp_path / "sphere.zip", check=True)
    script = ROOT / "examples" / "slurm" / "truth-array.sh"
    env = dict(os.environ, MESOLAB=BINARY, SIZE="40x32", SEED="4", SLURM_ARRAY_TASK_COUNT="3")
    for i in (2, 0, 1):  # array tasks run in any order
        subprocess.run(["bash", str(script), str(tmp_path / "sphere.zip"), "20", str(tmp_path / "parts")], env=dict(env, SLURM_ARRAY_TASK_ID=str(i)),
                       check=True, capture_output=True)
    parts = sorted((tmp_path / "parts").glob("*.truth"))
    assert [p.name.split(".samples-")[1] for p in parts] == ["0-8.truth", "16-20.truth", "8-16.truth"]
    cli("truth", "merge", *parts, "-o", tmp_path / "merged", check=True)
    cli("capture", tmp_path / "sphere.zip", "--backend", "truth", "--spp", "20", "--seed", "4", "--size", "40x32", "--no-cache", "-o", tmp_path / "one",
        check=True)
    name = mesolab.load_preset(PRESETS / "basic" / "sphere.json").name
    assert (tmp_path / "merged" / f"{name}.png").read_bytes() == (tmp_path / "one" / f"{name}.png").read_bytes()
