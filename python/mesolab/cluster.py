"""mesolab on a Dask.distributed cluster: `client=` on Workbench.render (the truth), sweep,
frontier and bench.

[SECTION] index
  Front     Workbench, sweep, frontier, bench: the core's own, or spread over `client`'s workers
  Truth     a truth as blocks of samples on the workers, merged to the one-process bytes
  Points    a sweep's settings, a frontier's settings per distance (in its two rounds) and a bench's rows as tasks
  Tasks     what runs on a worker: one Workbench per worker process, scenes by their pack's hash
  Local     local_cluster: a scheduler and workers on this machine
  Checks    workers, the GL resource, one build; progress and cancelling

How the work travels: the scene goes as a pack (mesolab.Scene -> zip bytes, core/pack.h), scattered
once to every worker under its content's hash and unpacked once per machine into the cache's
packs/ folder; each task names the pack, so a worker that has it does not receive it again. A
truth is split into blocks of samples (multiples of the path tracer's own block of samples); each
block's exact sums come back as a partial truth (what `capture --samples A:B` writes) and are
joined by the same code as `mesolab truth merge`: integer sums, so the merged truth is the
one-process truth's bytes whatever the number of workers and the order the blocks finish in, for
one build and instruction set (each part records its build; parts of two builds are refused).
A worker process that dies has its task rerun by the scheduler on another worker.

A task that needs OpenGL (backend "gpu", a bench's GPU columns) asks for the Dask resource "GL":
start such workers with `dask worker tcp://HOST:8786 --resources GL=1`. Ctrl-C (or a progress
callback that raises) cancels the queued tasks and sets a distributed.Event that running tasks
poll from their progress reports, so they stop at their next check.
"""
import contextlib
import os
import pathlib
import signal
import subprocess
import sys
import tempfile
import threading
import time
import uuid

from . import _mesolab as _core

_TRUTH_AOVS = ("radiance", "normal", "truth_stderr", "exitance", "irradiance")


class Stopped(Exception):
    """A task stopped because its run was cancelled (Ctrl-C or an error on the caller's side)."""


# [SECTION] Front
class Workbench(_core.Workbench):
    __doc__ = _core.Workbench.__doc__

    def render(self, scene, *, client=None, block=None, **kwargs):
        if client is None:
            if block is not None:
                raise _core.InputError("block= sets the samples per task of a truth spread over a cluster; add client=")
            return _core.Workbench.render(self, scene, **kwargs)
        return render_truth(self, scene, client, block=block, **kwargs)


Workbench.render.__doc__ = (_core.Workbench.render.__doc__ or "") + (
    "\n\nclient=: a distributed.Client; the truth (backend='truth', spp=) is rendered on its workers in blocks of block= "
    "samples (default: two blocks per worker thread) and merged into the bytes this workbench would render (kept in the "
    "truth cache as if rendered here). With noise= (and time_limit=, spp= the most samples) in rounds until the target: "
    "frame.truth['ended'] says what ended it; mesolab.cluster.last_run['rounds'] the samples and noise of each round."
)


def sweep(scene, *, client=None, **kwargs):
    """mesolab's sweep (see the core's help below); with client= each setting is a task on the cluster."""
    if client is None:
        return _core.sweep(scene, **kwargs)
    return _sweep_on(client, scene, **kwargs)


def frontier(scene, *, client=None, **kwargs):
    """mesolab's frontier; with client= each distance's truth is spread in blocks and each setting at each distance is a task.
    budget= is then the points' wall clock on the caller (the distances run at once and share it; the truths, spread first, are
    not counted); last_run holds budget_reached, skipped, markdown and written (files with out_dir=)."""
    if client is None:
        return _core.frontier(scene, **kwargs)
    return _frontier_on(client, scene, **kwargs)


def bench(tables=None, *, client=None, **kwargs):
    """mesolab's bench; with client= each row of each table is a task on the cluster."""
    if client is None:
        return _core.bench(tables, **kwargs)
    return _bench_on(client, tables, **kwargs)


for _f, _core_f in ((sweep, _core.sweep), (frontier, _core.frontier), (bench, _core.bench)):
    _f.__doc__ = _f.__doc__ + "\n\n" + (_core_f.__doc__ or "")


# [SECTION] Truth
def _blocks(first, end, threads, block):
    """[(a, b)] covering [first, end): `block` samples each (a multiple of the path tracer's block), else two per thread."""
    step = _core._truth_block
    if block is None:
        block = max(step, -(-(end - first) // max(1, 2 * threads)))
    elif int(block) < 1:
        raise _core.InputError(f"block={block}: expected samples per task, 1 or more")
    block = -(-int(block) // step) * step
    ranges, a = [], first
    while a < end:  # boundaries on multiples of the block (the path tracer's blocks stay aligned when `first` is not)
        b = min(end, (a // block + 1) * block)
        ranges.append((a, b))
        a = b
    return ranges


def _cached(client, scene, size, seed, spp):
    """The caller's cached truth of `scene` (samples [0, n), n <= spp) as a partial truth and its future on the cluster, to
    continue rather than render again: (bytes, n, future), or (None, 0, None)."""
    part = _core._truth_cached(scene, size, seed)
    n = _core._truth_part_info(part)["end"] if part is not None else 0
    if part is None or n > spp:
        return None, 0, None
    [future] = client.scatter([dict(part=part, first=0, end=n, tasks=[])], hash=False)
    return part, n, future


def render_truth(wb, scene, client, *, size=(512, 512), backend="truth", aovs=(), spp=None, seed=1, noise=None, time_limit=None,
                 progress=None, block=None):
    """The truth of `scene` rendered on `client`'s workers in blocks of samples and merged (the one-process bytes)."""
    if backend != "truth":
        raise _core.InputError(f"client=: backend={backend!r} renders a frame in milliseconds on this machine; a cluster spreads the truth "
                               "(backend='truth'), sweeps, frontiers and benches")
    for a in aovs:
        if a not in _TRUTH_AOVS:
            raise _core.InputError(f"aovs: the truth does not write '{a}' (it writes {', '.join(_TRUTH_AOVS)})")
    st = _core._truth_sampling(spp, noise, time_limit, seed)  # checked as one process checks them
    if not st["noise"] and not st["time_limit"]:
        merged = truth_on(client, scene, size=size, spp=st["spp"], seed=seed, block=block, progress=progress)
        return wb._truth_from_part(scene, merged)
    merged, ended = truth_to_target(client, scene, size=size, spp=st["spp"], seed=seed, noise=st["noise"], time_limit=st["time_limit"],
                                    block=block, progress=progress)
    return wb._truth_from_part(scene, merged, noise=st["noise"], time_limit=st["time_limit"], ended=ended)


def _spread(client, pack_future, digest, size, seed, ranges, event, run, prior=None):
    """The blocks `ranges` as tasks, and their merge on the workers, neighbours two by two (a tree), after `prior` (a merged
    part's future of the samples before them) when given: (block futures, merge futures, the last merge's or only future)."""
    futures = [client.submit(_truth_task, pack_future, digest, size, int(seed), a, b, event, key=f"mesolab-truth-{digest}-{a}-{b}-{run}")
               for a, b in ranges]
    merges, level = [], ([prior] if prior is not None else []) + futures
    while len(level) > 1:
        nxt = [client.submit(_merge_task, level[i], level[i + 1], key=f"mesolab-merge-{digest}-{ranges[0][0]}-{len(merges) + i // 2}-{run}")
               for i in range(0, len(level) - 1, 2)]
        merges += nxt
        level = nxt + level[len(level) - len(level) % 2:]
    return futures, merges, level[0]


def truth_on(client, scene, *, size, spp, seed=1, block=None, progress=None, pack=None):
    """The merged partial truth's bytes of samples [0, spp) of `scene`, rendered on the cluster."""
    spp = int(spp)
    if spp < 1:
        raise _core.InputError(f"spp={spp}: expected 1 or more samples per pixel")
    threads = _threads(client)
    size = tuple(int(x) for x in size)
    cached, start, prior = _cached(client, scene, size, seed, spp)  # this machine's samples so far are continued, not rendered again
    last_run.clear()
    if start == spp:
        last_run.update(tasks=[], cached_spp=start)
        return cached
    blocks = _blocks(start, spp, threads, block)
    if pack is None:
        pack = _core._pack_bytes(scene)
    pack_future, digest = _send_pack(client, pack)
    run = uuid.uuid4().hex[:12]
    event = f"mesolab-cancel-{run}"
    futures, merges, root = _spread(client, pack_future, digest, size, seed, blocks, event, run, prior=prior)
    t0 = time.perf_counter()
    _collect(client, futures, event, progress, f"truth of {scene.name}: blocks of {blocks[0][1] - blocks[0][0]} samples", fetch=False,
             others=merges)
    t1 = time.perf_counter()
    result = _collect(client, [root], event, None, "merge", others=futures + merges)[0]
    _one_build([(t["worker"], t["build"]) for t in result["tasks"]])
    last_run.update(tasks=[{k: t[k] for k in ("first", "end", "worker", "seconds")} for t in result["tasks"]], wait_s=t1 - t0,
                    merge_s=time.perf_counter() - t1, merges=len(merges), pack_bytes=len(pack), cached_spp=start)
    return result["part"]


def truth_to_target(client, scene, *, size, spp, seed=1, noise=0.0, time_limit=0.0, block=None, progress=None, pack=None):
    """Samples [0, N) of `scene`'s truth on the cluster, in rounds: each round's blocks are merged after the rounds before, on
    the workers, and its noise_rel measured there; the next round asks for the samples the 1/sqrt(n) law says the target needs
    (and a tenth more), within what time_limit leaves at the rounds' pace and spp. Ends after the round that reaches `noise`,
    passes `time_limit` seconds or reaches `spp` samples: (the merged part's bytes, what ended it: noise, time limit or samples).
    The bytes are the one-process truth of N samples."""
    threads = _threads(client)
    step = _core._truth_block
    size = tuple(int(x) for x in size)
    spp = int(spp)
    cached, done, root = _cached(client, scene, size, seed, spp)  # this machine's samples so far are continued, not rendered again
    last_run.clear()
    if cached is not None:
        reached = _core._truth_part_noise(cached) if done >= _core._noise_min_spp else float("inf")
        ended = "noise" if noise and reached <= noise else "samples" if done >= spp else None
        if ended:
            last_run.update(tasks=[], rounds=[], ended=ended, cached_spp=done)
            return cached, ended
    if pack is None:
        pack = _core._pack_bytes(scene)
    pack_future, digest = _send_pack(client, pack)
    run = uuid.uuid4().hex[:12]
    event = f"mesolab-cancel-{run}"
    t0 = time.monotonic()
    rounds, start = [], done
    end = min(spp, -(-max(_core._noise_min_spp, done + 2 * threads * step) // step) * step)  # rounds end on the tracer's blocks
    if cached is not None and noise and reached < float("inf") and not time_limit:  # what the 1/sqrt(n) law asks of the cached samples'
        # noise (with a time limit, a first round of the least size measures the pace)
        end = min(spp, max(end, -(-int(done * (reached / noise) ** 2 * 1.1) // step) * step))
    while True:
        ranges = _blocks(done, end, threads, block)
        futures, merges, root = _spread(client, pack_future, digest, size, seed, ranges, event, run, prior=root)
        measured = client.submit(_noise_task, root, key=f"mesolab-noise-{digest}-{end}-{run}")
        every = futures + merges + [measured]  # this round's (the rounds before are released once merged into `root`)
        reached = _collect(client, [measured], event, None, "noise", others=every)[0]
        done, elapsed = end, time.monotonic() - t0
        rounds.append(dict(end=done, noise_rel=reached, seconds=elapsed))
        ended = ("noise" if noise and reached <= noise else "samples" if done >= spp else "time limit" if time_limit and elapsed >= time_limit
                 else None)
        if progress is not None:
            target = f" (target {noise:.2%})" if noise else ""
            fraction = min(1.0, (noise / reached) ** 2) if noise and reached > 0 else 0.0
            if time_limit:
                fraction = max(fraction, min(1.0, elapsed / time_limit))
            progress(f"truth of {scene.name}: {done} spp, noise {reached:.2%}{target}", 1.0 if ended else fraction)
        if ended:
            break
        want = done + 2 * threads * step
        if noise and reached > 0:
            want = max(want, int(done * (reached / noise) ** 2 * 1.1))
        if time_limit:  # what the time left allows at the rounds' pace so far
            want = min(want, max(done + step, int(done + (time_limit - elapsed) * (done - start) / elapsed)))
        end = min(spp, -(-want // step) * step)
    result = _collect(client, [root], event, None, "merge", others=every)[0]
    _one_build([(t["worker"], t["build"]) for t in result["tasks"]])
    last_run.update(tasks=[{k: t[k] for k in ("first", "end", "worker", "seconds")} for t in result["tasks"]], rounds=rounds, ended=ended,
                    pack_bytes=len(pack), cached_spp=start)
    return result["part"], ended


# What the last truth spread over a cluster did: its tasks ({first, end, worker, seconds: the task's time on its worker}),
# the caller's wait for the blocks and then for the last merges and the merged truth (seconds), the merge tasks, the pack's
# size. For measuring a cluster's overhead.
last_run = {}


# [SECTION] Points
def _sweep_on(client, scene, *, knob, values, size=(256, 256), metric="rmse", backend="cpu", repeat=3, reference=None, by=None,
              by_values=None, spp=None, seed=1, noise=None, time_limit=None, out_dir=None, memory_limit=None, progress=None):
    if out_dir is not None:
        raise _core.InputError("client=: out_dir= writes a one-machine sweep's files; on a cluster the points come back as values")
    if (noise is not None or time_limit is not None) and metric != "truth":
        raise _core.InputError("client=: noise= and time_limit= set the truth of a sweep with metric='truth'; this sweep's metric is " + repr(metric))
    values = list(values)
    if by is not None and by_values is None:
        raise _core.InputError("sweep: by= needs by_values=[...]")
    by_list = list(by_values) if by is not None else [None]
    if metric != "truth":
        reference = _core._sweep_reference(scene, knob, values, reference)
    if backend == "gpu":
        _need_gl(client, "backend='gpu'")
    st = _core._truth_sampling(spp, noise, time_limit, seed)
    scenes = {}
    for b in by_list:
        for v in values:
            s = scene.copy()
            if by is not None:
                s[by] = b
            s[knob] = v
            scenes[(_key(b), _key(v))] = s
    samples = {k: st["spp"] for k in scenes}
    if metric == "truth":  # each distinct truth once, spread in blocks, then kept by every worker
        samples = dict(zip(scenes, _truths_everywhere(client, list(scenes.values()), size, st, progress)))
    pack = _core._pack_bytes(scene)
    pack_future, digest = _send_pack(client, pack)
    run = uuid.uuid4().hex[:12]
    event = f"mesolab-cancel-{run}"
    common = dict(knob=knob, size=tuple(size), metric=metric, backend=backend, repeat=repeat, reference=reference, seed=seed,
                  memory_limit=memory_limit)
    futures, order = [], []
    for b in by_list:
        for v in values:
            kw = dict(common, values=[v], spp=samples[(_key(b), _key(v))])
            if by is not None:
                kw.update(by=by, by_values=[b])
            futures.append(client.submit(_sweep_task, pack_future, digest, kw, event, key=f"mesolab-sweep-{digest}-{len(futures)}-{run}",
                                         resources={"GL": 1} if backend == "gpu" else None))
            order.append((b, v))
    results = _collect(client, futures, event, progress, f"sweep {knob}")
    points = []
    for (b, v), r in zip(order, results):
        p = dict(r["points"][0])
        p["value"] = v
        if by is not None:
            p["by"] = b
        p["worker"] = r["worker"]
        if metric == "truth":
            p["truth_spp"] = samples[(_key(b), _key(v))]  # its truth's samples (to noise=: what the rounds took)
        points.append(p)
    return points


def _frontier_on(client, scene, *, size=(128, 128), backend="cpu", distances=(), spp=None, seed=1, noise=None, time_limit=None, budget=600.0,
                 repeat=3, out_dir=None, memory_limit=None, progress=None):
    """The frontier's settings as tasks, in the one-process frontier's rounds: the first round (each method's preset, diagonal
    and knobs alone) at every distance, then, as a distance's first round completes, its second round between that round's
    frontier. Each point runs on a worker's kept Workbench (one at a time per worker process: its times are that process's
    alone) against the distance's truth, spread in blocks first and kept by every worker."""
    if backend == "gpu":
        _need_gl(client, "backend='gpu'")
    st = _core._truth_sampling(spp, noise, time_limit, seed)
    spp = st["spp"]
    options = dict(size=tuple(int(x) for x in size), backend=backend, distances=[float(d) for d in distances], spp=spp, seed=seed,
                   budget=float(budget), repeat=repeat, memory_limit=memory_limit)
    first_round = _core._frontier_settings(scene, options)  # the options and every setting checked before any work
    dists = options["distances"] or [scene["camera.distance"]]
    per_distance = []
    for d in dists:
        s = scene.copy()
        if options["distances"]:
            s["camera.distance"] = d
        per_distance.append(s)
    # Each distance's truth to spp= (or to noise=, time_limit=): its points ask for its samples, read from every worker's cache.
    samples = _truths_everywhere(client, per_distance, size, st, progress)
    pack_future, digest = _send_pack(client, _core._pack_bytes(scene))
    run = uuid.uuid4().hex[:12]
    event, budget_event = f"mesolab-cancel-{run}", f"mesolab-budget-{run}"
    resources = {"GL": 1} if backend == "gpu" else None
    from distributed import Event, as_completed
    ac = as_completed()
    meta = {}  # future key -> (distance index, round, index in the round, setting)
    futures = []

    def submit(j, rnd, i, setting, priority):
        f = client.submit(_frontier_point_task, pack_future, digest, dict(options, spp=samples[j]), dists[j], setting, event, budget_event,
                          key=f"mesolab-frontier-{digest}-{j}-{rnd}-{i}-{run}", priority=priority, resources=resources)
        meta[f.key] = (j, rnd, i, setting)
        futures.append(f)
        ac.add(f)

    for i, st in enumerate(first_round):  # the presets of every distance first, as the one process measures them first
        for j in range(len(dists)):
            submit(j, 1, i, st, -i)
    results = {}  # (distance index, round, index) -> the task's result
    first_left = [len(first_round)] * len(dists)
    deadline = time.monotonic() + float(budget)  # the points' wall clock (the truths before them are not counted)
    budget_reached, finished, last = False, 0, 0.0
    try:
        if progress is not None:
            progress(f"frontier of {scene.name}: 0 of {len(futures)} settings", 0.0)
        while not ac.is_empty():
            if not budget_reached and time.monotonic() > deadline:
                budget_reached = True  # running settings stop at their next check, queued ones are cancelled (not the presets)
                Event(budget_event, client=client).set()
                client.cancel([f for f in futures if f.status == "pending" and meta[f.key][3]["setting"] != "preset"])
            if not ac.has_ready():
                time.sleep(0.05)
                continue
            for f in ac.next_batch(block=False):
                j, rnd, i, st = meta[f.key]
                finished += 1
                if f.cancelled():
                    continue
                r = f.result()  # raises the task's error
                results[(j, rnd, i)] = r
                if rnd == 1:
                    first_left[j] -= 1
                    if first_left[j] == 0 and not budget_reached:
                        here = [results[(j, 1, k)]["point"] for k in range(len(first_round))
                                if (j, 1, k) in results and results[(j, 1, k)]["point"] is not None]
                        for k, b in enumerate(_core._frontier_between(scene, here)):
                            submit(j, 2, k, b, -len(first_round) - k)
                if progress is not None:
                    last = max(last, finished / len(futures))
                    progress(f"frontier of {scene.name}: {finished} of {len(futures)} settings", last)
    except BaseException:
        cancel(client, futures, event)
        raise
    # The points in the one-process frontier's order: by distance, then round, then setting.
    points, workers, machines, skipped, noise = [], [], set(), [], [0.0] * len(dists)
    for (j, rnd, i) in sorted(results):
        r = results[(j, rnd, i)]
        budget_reached = budget_reached or r["stopped"]
        if r["skipped"]:
            skipped.append(r["skipped"])
        if r["point"] is not None:
            points.append(r["point"])
            workers.append(r["worker"])
            machines.add(r["machine"])
            noise[j] = max(noise[j], r["truth_noise"])
    budget_reached = budget_reached or any(f.cancelled() for f in futures)
    n_workers = len(set(workers))
    machine = "; ".join(sorted(machines)) + f" ({n_workers} worker{'s' if n_workers != 1 else ''})"
    report = _core._frontier_report(scene, options, points, noise, budget_reached, skipped, machine, out_dir)
    last_run.clear()
    last_run.update(budget_reached=budget_reached, skipped=skipped, markdown=report["markdown"], written=report["written"], tasks=len(futures),
                    machine=machine, truth_spp=samples)
    return [dict(p, worker=w) for p, w in zip(report["points"], workers)]


def _bench_on(client, tables=None, *, repeat=5, backend="both", rows=(), columns=(), noise=None, time_limit=None, memory_limit=None, presets=None,
              progress=None):
    if backend not in ("cpu", "gpu", "both"):
        raise _core.InputError(f"backend={backend!r}: expected cpu, gpu or both")
    if backend != "cpu":
        _need_gl(client, f"backend={backend!r} (the GPU columns)")
    run = uuid.uuid4().hex[:12]
    event = f"mesolab-cancel-{run}"
    common = dict(repeat=repeat, backend=backend, columns=list(columns), noise=noise, time_limit=time_limit, memory_limit=memory_limit)
    resources = {"GL": 1} if backend != "cpu" else None
    futures = []
    if presets is not None:  # the truth table's rows are the user's scenes: each sent as a pack, a row on the worker that has it
        names = [str(t) for t in ([tables] if isinstance(tables, str) else tables or [])]
        if names != ["truth"]:
            raise _core.InputError("presets=: only the table truth takes presets (bench('truth', presets=[...]))")
        for i, path in enumerate(presets):
            scene = _core.load_preset(path)
            if rows and not any(f in scene.name for f in rows):
                continue
            pack_future, digest = _send_pack(client, _core._pack_bytes(scene))
            futures.append(client.submit(_bench_pack_task, pack_future, digest, scene.name, common, event, key=f"mesolab-bench-{i}-{run}",
                                         resources=resources))
    else:
        cells = [(t, r) for t, r in _core._bench_rows(tables) if not rows or any(f in r for f in rows)]
        futures = [client.submit(_bench_task, t, r, common, event, key=f"mesolab-bench-{i}-{run}", resources=resources)
                   for i, (t, r) in enumerate(cells)]
    if not futures:
        raise _core.InputError("bench: no row matches rows=" + repr(list(rows)))
    results = _collect(client, futures, event, progress, "bench")
    out = []
    for r in results:
        out.extend(dict(c, worker=r["worker"]) for c in r["cells"])
    return out


def _truths_everywhere(client, scenes, size, st, progress):
    """Each distinct truth of `scenes` rendered once on the cluster (to st's spp, or its noise target or time limit) and kept in
    every worker's truth cache. Returns each scene's truth's samples, in their order: the spp= its tasks ask for, so that every
    worker reads that truth from its cache, whatever ended it."""
    samples, by_key = [], {}
    for s in scenes:
        key = _core._truth_key(s, size, st["seed"])
        if key not in by_key:
            pack = _core._pack_bytes(s)
            if st["noise"] or st["time_limit"]:
                merged, _ = truth_to_target(client, s, size=size, spp=st["spp"], seed=st["seed"], noise=st["noise"], time_limit=st["time_limit"],
                                            progress=progress, pack=pack)
            else:
                merged = truth_on(client, s, size=size, spp=st["spp"], seed=st["seed"], progress=progress, pack=pack)
            client.run(_keep_truth_task, pack, _core._content_hash(pack), merged)
            by_key[key] = _core._truth_part_info(merged)["end"]
        samples.append(by_key[key])
    return samples


def _key(v):
    return repr(v)


# [SECTION] Tasks (run on the workers)
_worker_lock = threading.Lock()
_worker_wb = None
_worker_scenes = {}  # pack hash -> Scene


def _worker_name():
    try:
        from distributed import get_worker
        return get_worker().address
    except (ImportError, ValueError):
        return f"pid {os.getpid()}"


def _workbench():
    global _worker_wb
    with _worker_lock:
        if _worker_wb is None:
            _worker_wb = _core.Workbench()
        return _worker_wb


def _scene(pack, digest):
    with _worker_lock:
        s = _worker_scenes.get(digest)
        if s is None:
            s = _core._load_pack_bytes(pack, f"the pack {digest}")
            _worker_scenes[digest] = s
        return s.copy()


def _stopper(event_name):
    """A progress callback that raises once the caller has set the run's cancel event (checked every 0.2 s at most)."""
    from distributed import Event
    ev = Event(event_name)
    last = [0.0]

    def progress(stage, fraction):
        now = time.monotonic()
        if now - last[0] < 0.2:
            return
        last[0] = now
        if ev.is_set():
            raise Stopped(f"cancelled by the caller ({event_name})")

    return progress


def _test_exit_once(seed, first):
    """Test hook: MESOLAB_TEST_EXIT_ONCE=MARKER:SEED:FIRST makes the first attempt of the truth block (SEED, FIRST) exit its process."""
    spec = os.environ.get("MESOLAB_TEST_EXIT_ONCE")
    if not spec:
        return
    marker, s, f = spec.rsplit(":", 2)
    if int(s) != seed or int(f) != first:
        return
    try:
        fd = os.open(marker, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
    except FileExistsError:
        return
    os.close(fd)
    os._exit(75)


def _truth_task(pack, digest, size, seed, first, end, event):
    _test_exit_once(seed, first)
    t0 = time.perf_counter()
    scene = _scene(pack, digest)
    part = _workbench()._truth_part(scene, size, seed, first, end, progress=_stopper(event))
    task = dict(first=first, end=end, build=_core._truth_build(), worker=_worker_name(), seconds=time.perf_counter() - t0)  # the part's build
    return dict(part=part, first=first, end=end, tasks=[task])


def _merge_task(a, b):
    """Two neighbouring blocks' sums joined (exact: the same bytes in any grouping); a mixed build is refused by the merge."""
    name = lambda r: "samples {}:{} from {}".format(r["first"], r["end"], ", ".join(sorted({t["worker"] for t in r["tasks"]})))
    part = _core._merge_truth_parts([(name(a), a["part"]), (name(b), b["part"])])
    return dict(part=part, first=min(a["first"], b["first"]), end=max(a["end"], b["end"]), tasks=a["tasks"] + b["tasks"])


def _noise_task(r):
    return _core._truth_part_noise(r["part"])


def _keep_truth_task(pack, digest, merged):
    _workbench()._truth_from_part(_scene(pack, digest), merged)
    return True


def _sweep_task(pack, digest, kwargs, event):
    points = _core.sweep(_scene(pack, digest), progress=_stopper(event), _on=_workbench(), **kwargs)
    return dict(points=points, worker=_worker_name())


def _frontier_point_task(pack, digest, options, distance, setting, event, budget_event):
    from distributed import Event
    cancelled, budget = Event(event), Event(budget_event)
    last, over = [0.0], [False]

    def poll():  # the events every 0.2 s at most (each a round trip to the scheduler); True once the budget has ended
        now = time.monotonic()
        if now - last[0] >= 0.2:
            last[0] = now
            if cancelled.is_set():
                raise Stopped(f"cancelled by the caller ({event})")
            over[0] = over[0] or budget.is_set()
        return over[0]

    poll()
    r = _workbench()._frontier_point(_scene(pack, digest), options, distance, setting, poll=poll)
    r["worker"] = _worker_name()
    return r


def _bench_pack_task(pack, digest, name, kwargs, event):
    folder = _scene(pack, digest).base_dir  # the pack, unpacked on this worker: a folder pack
    cells = _core.bench("truth", presets=[folder], progress=_stopper(event), _on=_workbench(), **kwargs)
    return dict(cells=[dict(c, row=name) for c in cells], worker=_worker_name())


def _bench_task(table, row, kwargs, event):
    cells = _core.bench([table], rows=[row], progress=_stopper(event), _on=_workbench(), **kwargs)
    return dict(cells=[c for c in cells if c["row"] == row], worker=_worker_name())


# [SECTION] A cluster on this machine
@contextlib.contextmanager
def local_cluster(workers=2, *, threads=1, folder=None, own_caches=True, env=None):
    """A `dask scheduler` and `workers` `dask worker` processes on 127.0.0.1, each of `threads` threads
    (MESOLAB_THREADS=threads), for trying a cluster, or measuring one, on this machine: yields a
    distributed.Client and stops the processes at the end. folder: where their files go (default: a
    new temporary folder); own_caches: each worker with a cache folder of its own there (nothing
    cached by this machine's earlier runs), else the usual one; env: more environment for them all.
    The workers are named w0, w1, ...; the scheduler's address is in FOLDER/scheduler.json."""
    import distributed
    folder = pathlib.Path(folder or tempfile.mkdtemp(prefix="mesolab-cluster-"))
    folder.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ, MESOLAB_THREADS=str(threads), PYTHONDONTWRITEBYTECODE="1", **(env or {}))
    log = open(folder / "cluster.log", "w")
    sched = folder / "scheduler.json"

    def start(args, extra=None):
        return subprocess.Popen([sys.executable, "-m", "dask", *args], env=dict(env, **(extra or {})), stdout=log, stderr=subprocess.STDOUT,
                                start_new_session=True)

    procs = [start(["scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard", "--scheduler-file", str(sched)])]
    try:
        deadline = time.monotonic() + 60
        while not sched.exists():
            if time.monotonic() > deadline or procs[0].poll() is not None:
                raise RuntimeError(f"local_cluster: the scheduler did not start (its log: {folder / 'cluster.log'})")
            time.sleep(0.1)
        for i in range(int(workers)):
            procs.append(start(["worker", "--scheduler-file", str(sched), "--nthreads", str(threads), "--no-dashboard", "--memory-limit", "0",
                                "--name", f"w{i}", "--local-directory", str(folder / f"w{i}")], {"MESOLAB_CACHE_DIR": str(folder / f"cache-w{i}")} if own_caches else None))
        with distributed.Client(scheduler_file=str(sched), timeout=60) as client:
            client.wait_for_workers(int(workers), timeout=120)
            yield client
    finally:
        for p in procs:
            try:
                os.killpg(p.pid, signal.SIGTERM)
            except ProcessLookupError:
                pass
        for p in procs:
            try:
                p.wait(timeout=30)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait()
        log.close()


# [SECTION] Checks
def _threads(client):
    """The cluster's worker threads; waits up to 30 s for a first worker."""
    n = sum(client.nthreads().values())
    if n == 0:
        try:
            client.wait_for_workers(1, timeout=30)
        except Exception:
            raise _core.InputError("client=: the cluster has no workers after 30 s; start some with `dask worker tcp://SCHEDULER:8786`") from None
        n = sum(client.nthreads().values())
    return n


def _need_gl(client, what):
    workers = client.scheduler_info().get("workers", {})
    if not any(w.get("resources", {}).get("GL", 0) >= 1 for w in workers.values()):
        raise _core.InputError(f"client=: {what} needs OpenGL, and none of the cluster's {len(workers)} workers declares the Dask resource GL; "
                               "start workers on machines with a GPU with `dask worker tcp://SCHEDULER:8786 --resources GL=1`")


def _one_build(worker_builds):
    here = _core._truth_build()
    others = sorted({(b, w) for w, b in worker_builds if b != here})
    if others:
        b, w = others[0]
        raise _core.InputError(f"client=: worker {w} renders with another build ({b}; here: {here}): a mixed cluster gives different bits, "
                               "so its samples are not merged; run workers of this build")


def _send_pack(client, pack):
    """The pack scattered to every worker once, under its content's hash: (future, hash)."""
    digest = _core._content_hash(pack)
    [future] = client.scatter([pack], broadcast=True, hash=True)
    return future, digest


def _collect(client, futures, event, progress, what, fetch=True, others=()):
    """The futures' results in their order (None each without fetch: they stay on the workers); progress(what, fraction)
    as they finish. Any exception (Ctrl-C, a failed task, a progress callback that raises) cancels the run (the futures and
    `others`): queued tasks are cancelled, running ones see the event."""
    from distributed import as_completed
    index = {f.key: i for i, f in enumerate(futures)}
    results = [None] * len(futures)
    done = 0
    try:
        if progress is not None:
            progress(f"{what}: 0 of {len(futures)} tasks", 0.0)
        for f in as_completed(futures):
            if fetch or f.status != "finished":
                results[index[f.key]] = f.result()  # raises the task's error
            done += 1
            if progress is not None:
                progress(f"{what}: {done} of {len(futures)} tasks", done / len(futures))
    except BaseException:
        cancel(client, list(futures) + list(others), event)
        raise
    return results


def cancel(client, futures, event):
    """Stops a run: its running tasks see `event` at their next progress check; its queued tasks are cancelled."""
    from distributed import Event
    try:
        Event(event, client=client).set()
    finally:
        client.cancel(futures)
