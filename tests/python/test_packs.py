# Packs from Python: scene.save(path, pack=True) carries the arrays given from Python (which a
# plain preset names in the saver's cache), mesolab.load_preset reads a pack, the moved pack renders
# the same bytes; a bad pack is an InputError naming the member.
import shutil
import zipfile

import numpy as np
import pytest

from conftest import PRESETS, cli


def _scene_with_an_array(mesolab):
    s = mesolab.load_preset(PRESETS / "basic" / "torus-sky.json")
    s["basic.albedo_map"] = (np.random.default_rng(7).random((24, 24, 3)) * 255).astype(np.uint8)
    return s


@pytest.mark.parametrize("target", ["shared.zip", "shared_folder"])
def test_a_pack_carries_arrays_and_renders_the_same_after_a_move(mesolab, wb, tmp_path, target):
    s = _scene_with_an_array(mesolab)
    want = wb.render(s, backend="cpu", size=(48, 40))
    s.save(tmp_path / "a.json")
    assert "arrays/" in (tmp_path / "a.json").read_text(), "a plain preset names the array in the saver's cache"
    s.save(tmp_path / target, pack=True)
    moved = tmp_path / "elsewhere" / target
    moved.parent.mkdir()
    shutil.move(str(tmp_path / target), str(moved))
    t = mesolab.load_preset(moved)
    assert t["basic.albedo_map"].startswith("files/") and t["env.map"].startswith("files/")
    got = wb.render(t, backend="cpu", size=(48, 40))
    assert got["radiance"].tobytes() == want["radiance"].tobytes()
    # The command line reads the same pack.
    code, out, err = cli("capture", moved, "--backend", "cpu", "--size", "48x40", "-o", tmp_path / "cli")
    assert code == 0, err


def test_a_path_ending_in_zip_is_saved_as_a_pack_and_the_bytes_are_the_same_each_time(mesolab, tmp_path):
    s = _scene_with_an_array(mesolab)
    s.save(tmp_path / "one.zip")
    s.save(tmp_path / "two.zip", pack=True)
    assert (tmp_path / "one.zip").read_bytes() == (tmp_path / "two.zip").read_bytes()
    names = zipfile.ZipFile(tmp_path / "one.zip").namelist()
    assert names[0] == "scene.json" and len(names) == 3, names


def test_a_bad_pack_names_the_member(mesolab, tmp_path):
    s = _scene_with_an_array(mesolab)
    s.save(tmp_path / "p.zip")
    with zipfile.ZipFile(tmp_path / "p.zip") as z, zipfile.ZipFile(tmp_path / "bad.zip", "w") as out:
        for name in z.namelist():
            data = z.read(name)
            if name.endswith(".png"):
                data = data[:-1] + bytes([data[-1] ^ 1])
                bad_member = name
            out.writestr(name, data)
        out.writestr("notes/readme.txt", "hello")
    with pytest.raises(mesolab.InputError, match="notes/readme.txt"):
        mesolab.load_preset(tmp_path / "bad.zip")
    with zipfile.ZipFile(tmp_path / "bad.zip") as z, zipfile.ZipFile(tmp_path / "bad2.zip", "w") as out:
        for name in z.namelist():
            if name != "notes/readme.txt":
                out.writestr(name, z.read(name))
    with pytest.raises(mesolab.InputError, match=bad_member.replace(".", r"\.") + ".*changed or damaged"):
        mesolab.load_preset(tmp_path / "bad2.zip")
    (tmp_path / "cut.zip").write_bytes((tmp_path / "p.zip").read_bytes()[:200])
    with pytest.raises(mesolab.InputError, match="cut.zip.*truncated"):
        mesolab.load_preset(tmp_path / "cut.zip")


def test_bench_measures_a_pack_as_a_truth_row(mesolab, tmp_path):
    s = mesolab.load_preset(PRESETS / "basic" / "sphere.json")
    s["geometry.resolution"] = 16
    s.save(tmp_path / "tiny.zip")
    cells = mesolab.bench("truth", presets=[tmp_path / "tiny.zip"], repeat=1, backend="cpu")
    assert {c["row"] for c in cells} == {s.name}
    with pytest.raises(mesolab.InputError, match="only the table truth"):
        mesolab.bench("basic", presets=[tmp_path / "tiny.zip"])
