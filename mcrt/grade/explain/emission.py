r"""A surface emitting light the scene does not give it: its material or colour read as an emitter.

Radiance is linear in what surfaces emit. mcrt renders the scene with each
diffuse surface s (each wall, the floor, the ceiling, a diffuse object)
emitting unit white radiance from its front, :math:`E_s`, at the basis's spp
and seed; with B the basis's render of the scene, :math:`U_s = E_s - B` is
what that emission adds (the shared seed cancels most of the noise), and
channel c of a colour e emitted adds :math:`e_c U_{s,c}` exactly. The family
is one surface emitting a colour e (its material read as an emitter, a
struct's emission field filled), :math:`e \odot U_s` for the best s, three
parameters: flexible (:attr:`~mcrt.grade.candidates.Candidate.flexible`), as
it takes up a share of any difference that sits on one surface. (An ambient
term, every surface emitting k times its albedo, was a family too: on the
unmet class's held-out roulette that never stops it left noise and was
claimed; it is no longer tried.)

Each amplitude is the weighted least-squares one (the fit's pixel weights),
never negative: a surface cannot absorb light it was not lit by.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.fit import Fit
from mcrt.grade.explain.basis import basis_renderer
from mcrt.grade.feedback import fmt_values as _fmt
from mcrt.scene import Lambertian, Scene

WHITE = (1.0, 1.0, 1.0)


def _emitting(scene: Scene) -> dict[str, Scene]:
    """{label: the scene with that diffuse surface alone emitting white} for every diffuse surface."""
    room = scene.room
    out = {}
    for i, w in enumerate(room.walls):
        walls = tuple(replace(x, emission=WHITE) if j == i else x for j, x in enumerate(room.walls))
        out[f"wall {''.join(w.corners)}"] = replace(scene, room=replace(room, walls=walls))
    out["the floor"] = replace(scene, room=replace(room, floor_emission=WHITE))
    out["the ceiling"] = replace(scene, room=replace(room, ceiling_emission=WHITE))
    for o in scene.objects:
        if isinstance(o.material, Lambertian):
            objs = tuple(replace(x, material=replace(x.material, emission=WHITE)) if x.name == o.name else x
                         for x in scene.objects)
            out[f"the {o.name}"] = replace(scene, objects=objs)
    return out


def _prepare(a, scene: Scene, render) -> dict:
    """{label: E_s} at the basis's spp and seed (the module docstring)."""
    img = basis_renderer(a, render)
    return {label: img(s) for label, s in _emitting(scene).items()}


def _amplitudes(w: np.ndarray, D: np.ndarray, M: np.ndarray) -> np.ndarray:
    """The weighted least-squares amplitude of model M for the difference D, channel by channel (pixel weights w),
    at least 0."""
    den = np.einsum("hwc,hwc->c", w * M, M)
    num = np.einsum("hwc,hwc->c", w * D, M)
    return np.maximum(np.divide(num, den, out=np.zeros(3), where=den > 0), 0.0)


def emission(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """The best one surface emitting (the module docstring)."""
    r = inputs.basis.extra.get(emission.name)
    if not r:
        return []
    base = inputs.basis.base.astype(np.float64)
    w = np.where(fit.ok, fit.w, 0.0)  # once for every surface
    best = None
    for label, E in r.items():
        u = E.astype(np.float64) - base
        e = _amplitudes(w, fit.D, u)
        change = e * u
        chi = fit.delta(change)
        if best is None or chi < best[0]:
            best = (chi, label, e, change)
    chi, label, e, change = best
    return [Candidate("object_emits", "one surface emitting", f"{label} emitting light (radiance {_fmt(e)}) that the "
                      "scene does not give it (its material or colour read as an emitter)", chi, 3,
                      value={"surface": label, "radiance": tuple(float(x) for x in e)}, change=change,
                      flexible=True)]


emission.name, emission.prepare = "emission", _prepare
