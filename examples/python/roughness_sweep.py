"""A sweep of a rough metal sphere's roughness, and each image's error against spp, plotted.

    pip install . matplotlib && python examples/python/roughness_sweep.py

Writes roughness_sweep.png: the RMSE of renders at 4 to 256 spp against a 2048-spp reference,
per roughness (log-log; Monte Carlo error falls as spp^-1/2), and the film's own estimate.
"""

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import rtgpu

SCENE = """
[camera]
look_from = [0, 1, 4]
look_at = [0, 0, 0]
vfov = 35
[render]
background = "sky"
[materials]
metal = { type = "conductor", metal = "Au", roughness = 0.3 }
floor = { type = "lambertian", albedo = { checker = { scale = 0.5, even = [0.8, 0.8, 0.8], odd = [0.2, 0.2, 0.2] } } }
[[object]]
sphere = { center = [0, 0, 0], radius = 1 }
material = "metal"
[[object]]
quad = { q = [-10, -1, 10], u = [20, 0, 0], v = [0, 0, -20] }
material = "floor"
"""

scene = rtgpu.load_string(SCENE, name="sweep")
size = (96, 64)
ladder = [4, 16, 64, 256]
fig, ax = plt.subplots(figsize=(6, 4))
for roughness in [0.05, 0.2, 0.5, 1.0]:
    scene.set_material("metal", roughness=roughness)
    reference = rtgpu.render(scene, spp=2048, size=size, seed=99).image
    errors, estimates = [], []
    for spp in ladder:
        r = rtgpu.render(scene, spp=spp, size=size, seed=1)
        errors.append(np.sqrt(np.mean((r.image - reference) ** 2)))
        estimates.append(r.estimated_rmse)
    line = ax.loglog(ladder, errors, "o-", label=f"roughness {roughness}")[0]
    ax.loglog(ladder, estimates, "x--", color=line.get_color(), alpha=0.6)
    print(f"roughness {roughness}: RMSE " + ", ".join(f"{e:.4f}" for e in errors))
ax.set_xlabel("samples per pixel")
ax.set_ylabel("RMSE")
ax.set_title("o: against a 2048-spp reference; x: the film's own estimate", fontsize=9)
ax.legend()
fig.tight_layout()
fig.savefig("roughness_sweep.png", dpi=120)
print("wrote roughness_sweep.png")
