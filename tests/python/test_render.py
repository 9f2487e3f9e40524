# Frames from Python: arrays of the right shape and values, equal to `mesolab capture` on the CPU,
# the capture's files, every error path, progress, cancellation and two workbenches at once.
import _thread
import threading
import time

import numpy as np
import pytest

from conftest import PRESETS, cli

SPHERE = PRESETS / "basic" / "sphere.json"
SHADOWS = PRESETS / "microgeom" / "fig10a-shadows.json"


def test_radiance_is_a_read_only_float_array_of_the_frame(mesolab, wb):
    f = wb.render(mesolab.load_preset(SPHERE), size=(32, 24), backend="cpu", aovs=["normal"])
    rad = f["radiance"]
    assert rad.shape == (24, 32, 3) and rad.dtype == np.float32
    assert f.aovs == ["radiance", "normal"] and f.size == (32, 24)
    assert rad.max() > 0.05 and rad.min() >= 0  # the sphere is lit
    with pytest.raises(ValueError):
        rad[0, 0, 0] = 1
    assert f["normal"].shape == (24, 32, 3)
    with pytest.raises(KeyError, match="no AOV 'depth'"):
        f["depth"]
    assert f.renderer == "cpu"
    assert f.timings["render_ms"] > 0
    assert any(s["name"] == "scene.geometry" for s in f.stages)


def test_one_channel_aovs_have_a_last_axis_of_one(mesolab, wb):
    s = mesolab.load_preset(SHADOWS)
    s["microgeom.resolution"] = 16
    s["microgeom.directions"] = 20
    f = wb.render(s, size=(20, 16), backend="cpu", aovs=["shadow"])
    assert f["shadow"].shape == (16, 20, 1)
    assert 0 <= f["shadow"].min() and f["shadow"].max() <= 1


def test_a_cpu_frame_equals_the_capture_bit_for_bit(mesolab, wb, tmp_path):
    OpenImageIO = pytest.importorskip("OpenImageIO")
    s = mesolab.load_preset(SPHERE)
    f = wb.render(s, size=(40, 30), backend="cpu", aovs=["normal"])
    cli("capture", SPHERE, "--backend", "cpu", "--size", "40x30", "--aov", "radiance", "--aov", "normal", "-o", tmp_path, check=True)
    for aov in ("radiance", "normal"):
        exr = OpenImageIO.ImageBuf(str(tmp_path / f"{s.name}.{aov}.exr")).get_pixels(OpenImageIO.FLOAT)
        assert np.array_equal(exr, f[aov]), aov


def test_save_writes_the_capture_files_and_sidecar(mesolab, wb, tmp_path):
    import json
    s = mesolab.load_preset(SPHERE)
    f = wb.render(s, size=(16, 16), backend="cpu", aovs=["normal"])
    written = f.save(tmp_path / "out")
    names = sorted(p.rsplit("/", 1)[-1] for p in written)
    assert names == sorted([f"{s.name}.png", f"{s.name}.radiance.exr", f"{s.name}.normal.exr", f"{s.name}.json"])
    side = json.loads((tmp_path / "out" / f"{s.name}.json").read_text())
    assert side["renderer"] == "cpu" and side["size"] == [16, 16]
    assert mesolab.Scene.from_json(json.dumps(side["parameters"]), base_dir=str(SPHERE.parent)) == s
    assert f._repr_png_().startswith(b"\x89PNG\r\n\x1a\n")


def test_the_gpu_frame_agrees_with_the_cpu_frame(mesolab, wb):
    s = mesolab.load_preset(SPHERE)
    cpu = wb.render(s, size=(48, 48), backend="cpu")["radiance"]
    gpu = wb.render(s, size=(48, 48), backend="gpu")["radiance"]
    assert cpu.max() > 0.05 and gpu.max() > 0.05
    assert np.mean(np.abs(cpu - gpu)) < 0.01


def test_the_truth_renders_with_spp_and_seed(mesolab, wb):
    s = mesolab.load_preset(SPHERE)
    a = wb.render(s, size=(12, 12), backend="truth", spp=2, seed=3)
    b = wb.render(s, size=(12, 12), backend="truth", spp=2, seed=3)
    assert a.renderer == "truth" and np.array_equal(a["radiance"], b["radiance"])
    assert a.truth["spp"] == 2 and a.truth["seed"] == 3
    with pytest.raises(mesolab.InputError, match="spp"):
        wb.render(s, size=(12, 12), backend="truth", spp=0)


def test_the_truth_samples_to_a_noise_target_and_says_what_ended_it(mesolab, wb):
    s = mesolab.load_preset(SPHERE)
    f = wb.render(s, size=(16, 16), backend="truth", noise=0.05, seed=4)
    assert f.truth["ended"] == "noise" and f.truth["noise_rel"] <= 0.05 and f.truth["spp"] >= 16
    assert f.truth["noise_target"] == 0.05
    capped = wb.render(s, size=(16, 16), backend="truth", noise=1e-6, spp=20, seed=4)
    assert capped.truth["ended"] == "samples" and capped.truth["spp"] == 20
    timed = wb.render(s, size=(16, 16), backend="truth", noise=1e-6, time_limit=1e-6, seed=5)
    assert timed.truth["ended"] == "time limit"
    with pytest.raises(mesolab.InputError, match="noise=2"):
        wb.render(s, size=(16, 16), backend="truth", noise=2)
    with pytest.raises(mesolab.InputError, match="time_limit=-1"):
        wb.render(s, size=(16, 16), backend="truth", time_limit=-1)


def test_render_errors_are_input_errors(mesolab, wb):
    s = mesolab.load_preset(SPHERE)
    with pytest.raises(mesolab.InputError, match="is not one of gpu|cpu|truth"):
        wb.render(s, backend="vulkan")
    with pytest.raises(mesolab.InputError, match="size"):
        wb.render(s, size=(0, 10), backend="cpu")
    with pytest.raises(mesolab.InputError, match="size"):
        wb.render(s, size="wide", backend="cpu")
    with pytest.raises(mesolab.InputError, match="curvature_of_space"):
        wb.render(s, size=(8, 8), backend="cpu", aovs=["curvature_of_space"])


def test_an_unused_key_is_reported_when_the_scene_is_rendered(mesolab, wb):
    s = mesolab.load_preset(SHADOWS)
    s["microgeom.ellipse_bend"] = 45  # only used with microgeom.shadows = ellipse
    with pytest.raises(mesolab.InputError, match="not used when microgeom.shadows is 'exact'"):
        wb.render(s, size=(8, 8), backend="cpu")
    s["microgeom.shadows"] = "ellipse"
    s["microgeom.resolution"] = 16
    s["microgeom.directions"] = 20
    wb.render(s, size=(8, 8), backend="cpu")


def test_the_memory_budget_is_its_own_input_error(mesolab):
    small = mesolab.Workbench(memory_limit="1M")
    s = mesolab.load_preset(SPHERE)
    with pytest.raises(mesolab.MemoryBudgetError, match="more than the --memory-limit") as e:
        small.render(s, size=(2000, 2000), backend="cpu")
    assert isinstance(e.value, mesolab.InputError) and isinstance(e.value, ValueError)
    with pytest.raises(mesolab.InputError, match="memory"):
        mesolab.Workbench(memory_limit="lots")


def test_progress_reports_stages_and_a_raising_callback_stops_the_work(mesolab, wb):
    s = mesolab.load_preset(SHADOWS)
    s["microgeom.resolution"] = 64
    s["microgeom.directions"] = 60
    seen = []
    wb.clear_cache()
    wb.render(s, size=(16, 16), backend="cpu", progress=lambda stage, f: seen.append((stage, f)))
    assert seen and all(isinstance(n, str) and 0 <= f <= 1 for n, f in seen)

    class Stop(Exception):
        pass

    def stop(stage, f):
        raise Stop(stage)

    wb.clear_cache()
    with pytest.raises(Stop):
        wb.render(s, size=(16, 16), backend="cpu", progress=stop)
    assert wb.render(s, size=(16, 16), backend="cpu")["radiance"].max() > 0  # still usable


def test_ctrl_c_cancels_a_long_render_and_the_workbench_stays_usable(mesolab):
    w = mesolab.Workbench()
    s = mesolab.load_preset(SHADOWS)
    s["microgeom.resolution"] = 1024
    s["microgeom.directions"] = 400
    timer = threading.Timer(0.5, _thread.interrupt_main)
    t0 = time.monotonic()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        w.render(s, size=(16, 16), backend="cpu")
    assert time.monotonic() - t0 < 20  # stopped, not finished (minutes on 2 cores)
    s["microgeom.resolution"] = 16
    s["microgeom.directions"] = 20
    assert w.render(s, size=(16, 16), backend="cpu")["radiance"].shape == (16, 16, 3)


def test_two_workbenches_render_in_two_threads(mesolab):
    scenes = [mesolab.load_preset(SPHERE), mesolab.load_preset(PRESETS / "basic" / "torus-sky.json")]
    alone = [mesolab.Workbench().render(sc, size=(32, 32), backend=b)["radiance"] for sc, b in zip(scenes, ("cpu", "gpu"))]
    out = [None, None]
    errors = []

    def run(i, backend):
        try:
            w = mesolab.Workbench()
            for _ in range(3):
                out[i] = w.render(scenes[i], size=(32, 32), backend=backend)["radiance"]
        except Exception as e:  # pragma: no cover - reported below
            errors.append(e)

    threads = [threading.Thread(target=run, args=(0, "cpu")), threading.Thread(target=run, args=(1, "gpu"))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    assert np.array_equal(out[0], alone[0])
    assert np.allclose(out[1], alone[1], atol=1e-6)


def test_the_gil_is_released_while_rendering(mesolab):
    w = mesolab.Workbench()
    s = mesolab.load_preset(SHADOWS)
    s["microgeom.resolution"] = 256
    s["microgeom.directions"] = 100
    done = threading.Event()
    t = threading.Thread(target=lambda: (w.render(s, size=(16, 16), backend="cpu"), done.set()))
    t.start()
    spins = 0
    while not done.is_set() and t.is_alive():
        spins += 1  # Python runs here only while the render does not hold the GIL
        time.sleep(0.001)
    t.join()
    assert done.is_set() and spins > 20


def test_a_closed_workbench_says_so(mesolab):
    s = mesolab.load_preset(SPHERE)
    with mesolab.Workbench() as w:
        assert w.render(s, size=(8, 8), backend="gpu")["radiance"].shape == (8, 8, 3)
    with pytest.raises(mesolab.InputError, match="closed"):
        w.render(s, size=(8, 8), backend="cpu")
    w.close()  # twice is harmless
