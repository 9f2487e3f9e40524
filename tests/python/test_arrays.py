# Images given as numpy arrays: rendered as the same image in a file is, and cached by content.
import numpy as np
import pytest

from conftest import PRESETS

SHADOWS = PRESETS / "microgeom" / "fig10a-shadows.json"
SPHERE = PRESETS / "basic" / "sphere.json"


def write_image(path, array, oiio_type):
    OpenImageIO = pytest.importorskip("OpenImageIO")
    h, w = array.shape[:2]
    c = 1 if array.ndim == 2 else array.shape[2]
    out = OpenImageIO.ImageOutput.create(str(path))
    assert out.open(str(path), OpenImageIO.ImageSpec(w, h, c, oiio_type))
    assert out.write_image(array.reshape(h, w, c))  # OpenImageIO's Python reads (H, W, C)
    out.close()
    return str(path)


def test_a_heightfield_array_renders_as_the_same_file_and_is_cached_by_content(mesolab, tmp_path):
    wb = mesolab.Workbench()
    rng = np.random.default_rng(7)
    height = rng.random((24, 24), dtype=np.float32)
    base = mesolab.load_preset(SHADOWS)
    base["microgeom.directions"] = 20

    from_array = base.copy()
    from_array["microgeom.heightfield"] = height
    from_file = base.copy()
    from_file["microgeom.heightfield"] = write_image(tmp_path / "h.exr", height, "float")
    a = wb.render(from_array, size=(24, 24), backend="cpu")
    b = wb.render(from_file, size=(24, 24), backend="cpu")
    assert np.array_equal(a["radiance"], b["radiance"])
    assert a["radiance"].max() > 0

    same = base.copy()
    same["microgeom.heightfield"] = height.copy()  # the same contents: nothing recomputes
    assert all(s["status"] != "ran" for s in wb.render(same, size=(24, 24), backend="cpu").stages)
    other = base.copy()
    other["microgeom.heightfield"] = 0.5 * height  # other contents: the heightfield's stages run
    assert any(s["status"] == "ran" for s in wb.render(other, size=(24, 24), backend="cpu").stages)


def test_an_8_bit_albedo_array_means_what_an_8_bit_file_means(mesolab, tmp_path):
    wb = mesolab.Workbench()
    albedo = np.random.default_rng(3).integers(0, 256, (8, 16, 3), dtype=np.uint8)
    s = mesolab.load_preset(SPHERE)
    a, b = s.copy(), s.copy()
    a["basic.albedo_map"] = albedo
    b["basic.albedo_map"] = write_image(tmp_path / "albedo.png", albedo, "uint8")
    fa = wb.render(a, size=(32, 32), backend="cpu")
    fb = wb.render(b, size=(32, 32), backend="cpu")
    assert np.array_equal(fa["radiance"], fb["radiance"])


def test_arrays_that_are_no_image_are_refused(mesolab):
    s = mesolab.load_preset(SPHERE)
    with pytest.raises(mesolab.InputError, match="basic.albedo_map: expected a float, uint8 or uint16"):
        s["basic.albedo_map"] = np.zeros((4, 4), dtype=bool)
    with pytest.raises(mesolab.InputError, match="non-finite"):
        s["basic.albedo_map"] = np.full((4, 4, 3), np.nan, dtype=np.float32)
    with pytest.raises(mesolab.InputError, match="1 to 4 channels"):
        s["basic.albedo_map"] = np.zeros((4, 4, 7), dtype=np.float32)
    with pytest.raises(mesolab.InputError, match="expected numbers|out of range|expected"):
        s["basic.kd"] = np.zeros((2, 2), dtype=np.float32)  # not a file key: a vector is three numbers
