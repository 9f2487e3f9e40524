"""Accuracy against time: the sphere's tessellation swept from coarse to fine, each setting
rendered from a cold cache, its radiance compared with the finest setting's, and plotted.

    PYTHONPATH=build/python python3 examples/accuracy_vs_time.py [OUT_DIR] [--size N]
"""
import argparse
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

import mesolab

ROOT = pathlib.Path(__file__).resolve().parents[1]

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("out", nargs="?", default="examples-out")
parser.add_argument("--size", type=int, default=256)
args = parser.parse_args()

scene = mesolab.load_preset(ROOT / "presets" / "basic" / "sphere.json")
values = [6, 8, 12, 16, 24, 32, 48, 64, 128]
reference = 512  # the error of each setting is measured against this tessellation's frame
points = mesolab.sweep(scene, knob="geometry.resolution", values=values, size=(args.size, args.size), repeat=3,
                       reference={"geometry.resolution": reference},
                       progress=lambda stage, f: print(f"\r{stage} {100 * f:3.0f}%", end="", flush=True))
print()
for p in points:
    print(f"resolution {p['value']:4d}: {p['ms']:8.2f} ms, RMSE {p['error']:.2e} (relative {p['relative_error']:.2e})")

measured = [p for p in points if p["error"] > 0]  # a log axis has no place for an error of 0
fig, ax = plt.subplots(figsize=(6, 4))
ax.loglog([p["ms"] for p in measured], [p["relative_error"] for p in measured], "o-")
for p in measured:
    ax.annotate(str(p["value"]), (p["ms"], p["relative_error"]), textcoords="offset points", xytext=(4, 4), fontsize=8)
ax.set_xlabel("time per frame incl. stages, cold cache (ms)")
ax.set_ylabel("relative RMSE vs resolution %d" % reference)
ax.set_title("geometry.resolution on %s" % scene.name)
ax.grid(True, which="both", alpha=0.3)
out = pathlib.Path(args.out)
out.mkdir(parents=True, exist_ok=True)
fig.savefig(out / "accuracy_vs_time.png", dpi=100, bbox_inches="tight")
print(out / "accuracy_vs_time.png")
