"""Area against solid-angle light sampling at single receivers, near the light and far from it.

At a receiver x with normal n facing the light, the estimator's light
sample (:meth:`mcrt.estimator.PathEstimator.light_sample`) estimates the
irradiance E(x) = int Le V cos_x cos_y / d^2 dA. Sampled uniformly in area,
its weight Le cos_x cos_y A / d^2 grows without bound as x nears the light;
sampled uniformly in solid angle it is Le cos_x Omega(x) <= Le Omega(x).
For each receiver both strategies draw the same number of samples; the
study records the mean (both must agree with Lambert's closed form,
:func:`mcrt.closed_form.polygon_irradiance`), the per-sample variance, the
time per sample (the light-sample kernel alone, after a warm-up) and the
efficiency ratio var_area t_area / (var_solid t_solid).
"""

from __future__ import annotations

import math
import time

import numpy as np

from mcrt.scene import Scene

#: Distances below the light's centre of the receivers (facing it), from almost touching to the floor.
HEIGHTS = (0.01, 0.05, 0.25, 1.0, 4.0, 9.98)


def receivers(scene: Scene, heights=HEIGHTS) -> list[tuple[str, tuple, tuple]]:
    """(name, point, normal): points below the light's centre, normal towards it, and a floor corner far away."""
    light = scene.light
    c = np.asarray(light.center, dtype=float)
    n = -np.asarray(light.normal, dtype=float)  # a receiver below the light faces up at it
    out = [(f"{h:g} below the light", tuple(float(v) for v in c + np.asarray(light.normal) * h), tuple(float(v) for v in n))
           for h in heights]
    corner = max(scene.room.corners.values(), key=lambda p: (p[0] - c[0]) ** 2 + (p[1] - c[1]) ** 2)
    far = (0.95 * corner[0] + 0.05 * c[0], 0.95 * corner[1] + 0.05 * c[1], scene.room.floor_z + 1e-3)
    out.append(("floor, far corner", far, (0.0, 0.0, 1.0)))
    return out


def _sample(scene: Scene, strategy: str, x, n, samples: int, seed: int):
    import drjit as dr
    import drjit.llvm as m

    from mcrt.estimator import PathEstimator
    from mcrt.geometry import Geometry
    from mcrt.host import McrtHost
    from mcrt.options import EstimatorOptions
    from mcrt.rng import WeylRng

    host = McrtHost(Geometry(scene, m, "convex"))
    est = PathEstimator(host, EstimatorOptions.build(light_sampling=strategy))
    rng = WeylRng.seeded(m, samples, m.UInt32(seed), m.UInt32(seed + 1))
    # Opaque receivers: one kernel per strategy, not one per receiver.
    origin = m.Array3f(*(dr.opaque(m.Float, c, samples) for c in x))
    value = est.light_sample(origin, m.Array3f(*(dr.opaque(m.Float, c) for c in n)), rng, m.Bool(True))
    g = value[1]
    dr.eval(g)
    return g


def light_receiver_study(scene: Scene, *, samples: int = 1 << 20, seed: int = 11, repeats: int = 5) -> list[dict]:
    """Both strategies at every receiver of :func:`receivers`: mean, closed form, variance, time, efficiency ratio."""
    from mcrt.closed_form import polygon_irradiance

    rows = []
    for name, x, n in receivers(scene):
        expected = float(polygon_irradiance(np.array([x]), np.array([n]), scene.light.corners(), scene.light.radiance[1])[0])
        row = {"receiver": name, "point": list(x), "normal": list(n), "closed_form": expected,
               "distance": float(np.linalg.norm(np.asarray(x) - np.asarray(scene.light.center)))}
        for strategy in ("area", "solid_angle"):
            _sample(scene, strategy, x, n, samples, seed)  # compile
            t0 = time.perf_counter()
            for _ in range(repeats):
                g = _sample(scene, strategy, x, n, samples, seed)
            per_sample = (time.perf_counter() - t0) / (repeats * samples)
            a = np.asarray(g.numpy(), dtype=np.float64)
            row[strategy] = {"mean": float(a.mean()), "std_error": float(a.std(ddof=1) / math.sqrt(a.size)),
                             "variance": float(a.var(ddof=1)), "seconds_per_sample": per_sample}
        va, vs = row["area"]["variance"], row["solid_angle"]["variance"]
        ta, ts = row["area"]["seconds_per_sample"], row["solid_angle"]["seconds_per_sample"]
        row["variance_ratio"] = va / vs if vs > 0 else float("inf")
        row["efficiency_ratio"] = va * ta / (vs * ts) if vs > 0 else float("inf")
        rows.append(row)
    return rows
