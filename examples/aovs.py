"""A frame and its AOVs as numpy arrays: radiance, shading normal and the bump shadows of
Heidrich et al. 2000's Fig. 10 (bottom left), side by side; the frame's files as `mesolab capture`
writes them.

    PYTHONPATH=build/python python3 examples/aovs.py [OUT_DIR] [--size N]
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
args = parser.parse_args()

scene = mesolab.load_preset(ROOT / "presets" / "microgeom" / "fig10a-shadows.json")
scene["light.direction"] = [60, -30]
frame = mesolab.Workbench().render(scene, size=(args.size, args.size), backend="cpu", aovs=["normal", "shadow"])
print(frame)

fig, axes = plt.subplots(1, 3, figsize=(10, 3.6))
axes[0].imshow(np.clip(frame["radiance"], 0, 1) ** (1 / 2.2))
axes[0].set_title("radiance (sRGB for display)")
axes[1].imshow(0.5 + 0.5 * frame["normal"])
axes[1].set_title("normal")
shadow = axes[2].imshow(frame["shadow"][..., 0], cmap="gray", vmin=0, vmax=1)
axes[2].set_title("shadow (fraction of the light)")
fig.colorbar(shadow, ax=axes[2], fraction=0.046)
for ax in axes:
    ax.axis("off")
out = pathlib.Path(args.out)
out.mkdir(parents=True, exist_ok=True)
fig.savefig(out / "aovs.png", dpi=100, bbox_inches="tight")
print(out / "aovs.png")
print("capture files:", *frame.save(out / "capture"), sep="\n  ")
