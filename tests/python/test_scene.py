# Scenes from Python: presets load, keys are set and read with the CLI's checks and words, the
# JSON and the saved file round-trip.
import pathlib

import pytest

from conftest import PRESETS, cli_error

SPHERE = PRESETS / "basic" / "sphere.json"
TRIO = PRESETS / "basic" / "trio.json"


def test_values_come_back_as_plain_python_values(mesolab):
    s = mesolab.load_preset(SPHERE)
    assert s.get("basic.kd") == (0.75, 0.3, 0.2)
    assert s["camera.distance"] == 3.2
    assert s["geometry.resolution"] == 96 and type(s["geometry.resolution"]) is int
    assert s["camera.mode"] == "orbit"
    assert s["effects.environment"] is True
    s.set("light.direction", [60, 45])
    assert s["light.direction"] == (60.0, 45.0)
    s["basic.kd"] = (0.2, 0.5, 0.8)
    assert s.get("basic.kd", object=0) == (0.2, 0.5, 0.8)
    s["basic.shininess"] = 64.1  # a float as Python writes it comes back exactly
    assert s["basic.shininess"] == 64.1


def test_object_selects_one_object_by_index_or_name(mesolab):
    s = mesolab.load_preset(TRIO)
    names = [o["name"] for o in s.objects]
    assert len(names) >= 2
    basic = [i for i, o in enumerate(s.objects) if o["technique"] == "basic"]
    s.set("basic.kd", (0.1, 0.2, 0.3), object=basic[0])
    assert s.get("basic.kd", object=basic[0]) == (0.1, 0.2, 0.3)
    if len(basic) > 1:
        assert s.get("basic.kd", object=basic[1]) != (0.1, 0.2, 0.3)
    s.set("geometry.resolution", 12, object=names[-1])
    assert s.get("geometry.resolution", object=names[-1]) == 12
    with pytest.raises(mesolab.InputError, match="is not in the scene"):
        s.get("basic.kd", object="no such object")
    with pytest.raises(mesolab.InputError, match="out of range"):
        s.get("basic.kd", object=99)


@pytest.mark.parametrize("key,value,text", [
    ("basic.kd", (2, 2, 2), "2,2,2"),
    ("camera.distanse", 3, "3"),
    ("geometry.resolution", 1.5, "1.5"),
    ("camera.mode", "sideways", "sideways"),
    ("effects.environment", 3, "3"),
])
def test_errors_carry_the_words_of_the_command_line(mesolab, key, value, text):
    s = mesolab.load_preset(SPHERE)
    with pytest.raises(mesolab.InputError) as e:
        s.set(key, value)
    assert isinstance(e.value, ValueError)
    assert str(e.value) == cli_error("preset", "show", SPHERE, "--set", f"{key}={text}")


def test_a_bad_preset_is_an_input_error_naming_the_file(mesolab, tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text('{"schema": 1, "name": "x", "camera": {"distanse": 3}}')
    with pytest.raises(mesolab.InputError) as e:
        mesolab.load_preset(bad)
    assert str(e.value) == cli_error("preset", "validate", bad)
    assert "bad.json" in str(e.value) and "distanse" in str(e.value)
    with pytest.raises(mesolab.InputError, match="no such file|not found"):
        mesolab.load_preset(tmp_path / "missing.json")
    with pytest.raises(mesolab.InputError, match="scene JSON"):
        mesolab.Scene.from_json("{ not json")


def test_a_value_python_cannot_express_as_a_setting_is_refused(mesolab):
    s = mesolab.load_preset(SPHERE)
    with pytest.raises(mesolab.InputError, match="basic.kd"):
        s.set("basic.kd", {"r": 1})
    with pytest.raises(mesolab.InputError, match="expected numbers"):
        s.set("basic.kd", ["a", "b", "c"])


def test_json_and_saved_file_round_trip(mesolab, tmp_path):
    s = mesolab.load_preset(SPHERE)
    s["basic.kd"] = (0.2, 0.5, 0.8)
    s.name = "edited"
    again = mesolab.Scene.from_json(s.to_json(), base_dir=str(SPHERE.parent))
    assert again == s
    path = tmp_path / "edited.json"
    s.save(path)
    assert mesolab.load_preset(path) == s
    assert [p.name for p in tmp_path.iterdir()] == ["edited.json"]  # no temporary file left behind
    assert s.copy() == s and s.copy() is not s


def test_save_keeps_the_old_file_when_it_cannot_write(mesolab, tmp_path):
    path = tmp_path / "keep.json"
    path.write_text("old")
    s = mesolab.load_preset(SPHERE)
    with pytest.raises(Exception):
        s.save(path / "x.json")  # its folder would be a file
    assert path.read_text() == "old"


def test_schema_lists_every_key_with_type_range_and_help(mesolab):
    schema = mesolab.schema()
    kd = schema["basic.kd"]
    assert kd["type"] == "color" and kd["default"] and kd["help"]
    assert kd["cost"] in ("redraw", "recompute")
    assert schema["geometry.resolution"]["range"][0] == 3
    assert "orbit" in schema["camera.mode"]["range"]
    assert set(mesolab.schema("basic")) == {k for k in schema if k.startswith("basic.")}
    with pytest.raises(mesolab.InputError, match="did you mean 'basic'"):
        mesolab.schema("basik")


def test_version_and_info(mesolab):
    assert mesolab.__version__
    info = mesolab.info()
    assert info["version"] == mesolab.__version__
    assert "basic" in info["techniques"].split()
    assert "gl_renderer" in info or "gl" in info
    assert int(info["cpu_threads"]) >= 1


def test_update_sets_several_keys_with_the_same_checks(mesolab):
    s = mesolab.load_preset(SPHERE)
    s.update({"basic.kd": (0.1, 0.2, 0.3), "camera.distance": 5})
    assert s["basic.kd"] == (0.1, 0.2, 0.3) and s["camera.distance"] == 5.0
    with pytest.raises(mesolab.InputError, match="camera.distanse"):
        s.update({"camera.distanse": 4})
