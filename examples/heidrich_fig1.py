"""Heidrich et al. 2000, Fig. 1: the same ridged micro-geometry without and with light scattered
between its faces (4 bounces, 200 directions). The red faces stay black in (a) and are lit by the
white ones in (b).

    PYTHONPATH=build/python python3 examples/heidrich_fig1.py [OUT_DIR] [--size N]
"""
import argparse
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import mesolab

ROOT = pathlib.Path(__file__).resolve().parents[1]

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("out", nargs="?", default="examples-out")
parser.add_argument("--size", type=int, default=256)
parser.add_argument("--backend", default="cpu")
args = parser.parse_args()

wb = mesolab.Workbench()
panels = []
for name, title in (("fig1a-no-scattering", "(a) without scattering"), ("fig1b-scattering", "(b) 4 bounces of scattering")):
    scene = mesolab.load_preset(ROOT / "presets" / "microgeom" / f"{name}.json")
    frame = wb.render(scene, size=(args.size, args.size), backend=args.backend)
    stages = sum(s["ms"] for s in frame.stages if s["status"] == "ran")
    srgb = np.clip(frame["radiance"], 0, 1) ** (1 / 2.2)  # display only; the arrays are linear
    panels.append((srgb, f"{title}\nstages not cached before: {stages:.0f} ms; frame {frame.timings['render_ms']:.1f} ms"))

fig, axes = plt.subplots(1, 2, figsize=(8, 4.4))
for ax, (image, title) in zip(axes, panels):
    ax.imshow(image)
    ax.set_title(title, fontsize=9)
    ax.axis("off")
fig.suptitle("Heidrich et al. 2000, Fig. 1 (mesolab, %s backend)" % args.backend)
out = pathlib.Path(args.out)
out.mkdir(parents=True, exist_ok=True)
fig.savefig(out / "heidrich_fig1.png", dpi=100, bbox_inches="tight")
print(out / "heidrich_fig1.png")
