# bench and sweep from Python: the CLI's JSON cells and sweep points, errors as InputError, files
# only when asked for.
import pytest

from conftest import PRESETS


def test_bench_returns_the_json_cells(mesolab):
    cells = mesolab.bench("basic", repeat=1, backend="cpu", rows=["sphere 64"], columns=["frame 512"])
    assert cells, "no cell measured"
    for c in cells:
        assert c["table"] == "basic" and c["device"] == "cpu"
        assert c["median_ms"] > 0 and c["min_ms"] <= c["median_ms"] <= c["max_ms"]
    with pytest.raises(mesolab.InputError, match="unknown table 'basik'.*did you mean 'basic'"):
        mesolab.bench("basik")
    with pytest.raises(mesolab.InputError, match="no cell matches"):
        mesolab.bench("basic", rows=["no such row"], backend="cpu")


def test_sweep_returns_points_and_writes_files_only_when_asked(mesolab, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    s = mesolab.load_preset(PRESETS / "basic" / "sphere.json")
    values = [4, 8, 32]
    points = mesolab.sweep(s, knob="geometry.resolution", values=values, size=(24, 24), repeat=1, reference={"geometry.resolution": 32})
    assert [p["value"] for p in points] == values
    assert all(p["ms"] > 0 for p in points)
    assert points[-1]["error"] == 0  # the reference's own setting
    assert points[0]["error"] > points[1]["error"] > 0
    assert list(tmp_path.iterdir()) == []
    seen = []
    mesolab.sweep(s, knob="geometry.resolution", values=values, size=(24, 24), repeat=1, out_dir=tmp_path / "out",
                  progress=lambda stage, f: seen.append(stage))
    assert sorted(p.suffix for p in (tmp_path / "out").iterdir()) == [".csv", ".md", ".png", ".svg"]
    assert seen
    with pytest.raises(mesolab.InputError, match="geometry.resolutoin"):
        mesolab.sweep(s, knob="geometry.resolutoin", values=[4, 8])
    with pytest.raises(mesolab.InputError, match="values is empty"):
        mesolab.sweep(s, knob="geometry.resolution", values=[])


def test_a_raising_progress_callback_stops_bench_and_sweep(mesolab):
    class Stop(Exception):
        pass

    calls = []

    def stop(stage, f):
        calls.append(stage)
        raise Stop(stage)

    with pytest.raises(Stop, match="bench basic"):
        mesolab.bench("basic", repeat=50, backend="cpu", progress=stop)
    s = mesolab.load_preset(PRESETS / "basic" / "sphere.json")
    with pytest.raises(Stop, match="sweep geometry.resolution"):
        mesolab.sweep(s, knob="geometry.resolution", values=[8, 512], size=(64, 64), repeat=20, progress=stop)
    assert len(calls) == 2


def test_frontier_returns_points_on_one_truth(mesolab, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    s = mesolab.load_preset(PRESETS / "basic" / "sphere.json")
    points = mesolab.frontier(s, size=(24, 24), spp=4, repeat=1, distances=[3.0, 6.0])
    assert {p["distance"] for p in points} == {3.0, 6.0}
    assert all(p["frame_ms"] > 0 and p["rmse_rel"] > 0 for p in points)
    assert points[0]["setting"] == "preset" and points[0]["knobs"] == {"geometry.resolution": "96"}
    assert any(p["on_frontier"] for p in points)
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(mesolab.InputError, match="real-time renderer"):
        mesolab.frontier(s, backend="truth", budget=0)
