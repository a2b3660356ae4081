"""The Cornell box on both backends, compared: the GPU kernel and the CPU reference compute the
same estimator, so their images differ by noise alone.

    pip install . && python examples/python/compare_backends.py

Prints each backend's time; with one seed, how far apart the two images are (both draw the same
random numbers, so only arithmetic separates them); with two seeds, the difference's RMS against
the noise the films estimate (about 1: noise alone).
"""

import numpy as np

import rtgpu

scene = rtgpu.load("cornell")

def render(backend, seed):
    return rtgpu.render(scene, spp=64, size=(128, 128), backend=backend, seed=seed)


if not rtgpu.devices():
    raise SystemExit("no GPU adapter: nothing to compare the CPU backend with")
cpu, gpu = render("cpu", 7), render("gpu", 7)
for r in (cpu, gpu):
    print(f"{r.backend}: {r.device}, {r.seconds:.2f} s, estimated RMSE {r.estimated_rmse:.4f}")
print(f"same seed: largest difference {np.abs(cpu.image - gpu.image).max():.2e}")
other = render("gpu", 8)
noise = np.hypot(cpu.estimated_rmse, other.estimated_rmse)
rms = np.sqrt(np.mean((cpu.image - other.image) ** 2))
print(f"seeds 7 and 8: RMS difference {rms:.4f} against the films' noise {noise:.4f} ({rms / noise:.2f})")
