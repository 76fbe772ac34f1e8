r"""The light sampled with a wrong weight: the light seen right, the light it sheds on surfaces k times too much.

Next-event estimation weighs a light sample by :math:`1 / p`; a pdf taken
as 1 instead of :math:`1/A` (A the light's area), the area applied twice,
or half the light's surface sampled with the whole one's pdf, scales all
light that reaches a surface by one factor k and leaves the light seen
directly (no light sample) as it is. With :math:`D_1` mcrt's render cut at
depth 1 (the light seen directly) and B the full render (the basis's, one
seed),

.. math::

    M(k) = D_1 + k\,(B - D_1).

The light seen in the mirror sphere is a path that hits the light after a
specular bounce, not a light sample, yet it is scaled with the rest: an
approximation confined to a few of the sphere's pixels.

No free parameter: k is one of the factors a program gets wrong
(:func:`factors`: the light's area A or 1/A, 2 or 1/2, the number of shadow
rays a point sums where their mean belongs); a weight fitted
freely would mimic any small change of the light on the room (an adaptive
sampler's bias of -1 % is no light sample's weight of 0.99).

A light sample drawn on part of the light with the whole light's pdf (its
coordinates in [0, 1) where [-1, 1) was meant: one quadrant) sheds the
light's power from that part alone: the light on surfaces is that of the
quadrant at 4 times the radiance, :math:`B_q - D_{1,q}` (mcrt renders of
the scene with the light replaced by the brighter quadrant, full and cut at
depth 1), the light seen directly unchanged. Each quadrant is a candidate
with no free parameter.
"""

from __future__ import annotations

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.fit import Fit
from mcrt.grade.explain.light_twice import _depth
from mcrt.grade.feedback import num as _num


#: Shadow rays a program may trace from each point and sum, not average: a few powers of 2, ten, and the 30 of the
#: course report's renders.
SHADOW_RAYS = (4, 8, 10, 16, 30, 32)


def factors(area: float) -> tuple[tuple[float, str], ...]:
    """(k, what it means) of the light sample weights programs get wrong, for a light of ``area``."""
    return ((1.0 / area, f"1/A = {_num(1.0 / area)}: the light's pdf taken as 1, not 1/A"),
            (area, f"A = {_num(area)}: the light's area applied twice (its pdf taken as 1/A^2)"),
            (0.5, "1/2: half the light's surface sampled (one of its two triangles) with the whole light's pdf"),
            (2.0, "2: the light sampled with half its pdf (two triangles' samples both counted)"),
            *((float(n), f"{n}: {n} shadow rays a point summed where their mean belongs") for n in SHADOW_RAYS))


def _quadrants(scene):
    """(name, scene) with the light replaced by each quarter of itself at 4 times its radiance (the same power)."""
    from dataclasses import replace

    lt = scene.light
    hx, hy = lt.size[0] / 4, lt.size[1] / 4
    for sx, sy in ((1, 1), (-1, 1), (-1, -1), (1, -1)):
        q = replace(lt, center=(lt.center[0] + sx * hx, lt.center[1] + sy * hy, lt.center[2]),
                    size=(lt.size[0] / 2, lt.size[1] / 2), radiance=tuple(4.0 * r for r in lt.radiance))
        yield f"{'+' if sx > 0 else '-'}x {'+' if sy > 0 else '-'}y", replace(scene, light=q)


def _prepare(a, scene, render) -> dict[str, np.ndarray]:
    """quadrant -> the light it sheds on surfaces (its render minus its render cut at depth 1), basis spp and seed."""
    from mcrt.grade.explain.basis import basis_settings

    spp, seed = basis_settings(a)

    def img(s, depth):
        return render(s, a.camera, a.grade_width, a.grade_height, depth, spp, seed).mean.astype(np.float32)

    return {name: img(s, a.max_depth) - img(s, 1) for name, s in _quadrants(scene)}


def _quadrant(fit: Fit, inputs: Inputs, x: np.ndarray) -> Candidate | None:
    """The best quadrant of :func:`_quadrants` as the light sampled (the module docstring), None without renders."""
    quads = inputs.basis.extra.get(light_sampling.name)
    if not quads:
        return None
    err, name, change = min(((fit.delta(q - x), name, q - x) for name, q in
                             ((n, q.astype(np.float64)) for n, q in quads.items())), key=lambda t: t[0])
    text = (f"the light's samples drawn on one quarter of it (the {name} quarter) with the whole light's pdf: its "
            "light on surfaces comes from that quarter, 4 times as bright, the light itself seen right (sample "
            "coordinates drawn in [0, 1) where [-1, 1) was meant)")
    return Candidate("light_sampling", "light sampled on a quarter", text, err, 0, value={"quarter": name},
                     change=change)


def light_sampling(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """The light on surfaces k times the truth for the best k of :func:`factors`, and from the best quarter of the
    light (:func:`_quadrant`), the light seen directly unchanged (the module docstring)."""
    b = inputs.basis
    d1 = _depth(b, 1)
    size = b.values.get("light_size", (0.0, 0.0))
    area = float(size[0]) * float(size[1])
    if d1 is None or area <= 0:
        return []
    x = b.base.astype(np.float64) - d1  # what light sampling brings: k - 1 times it is the change
    err, k, words = min((fit.delta((k - 1.0) * x), k, words) for k, words in factors(area) if k != 1.0)
    text = (f"the light reaching surfaces {_num(k)} times what it should be, the light itself seen right: a light "
            f"sample weighted wrongly (k = {words})")
    out = [Candidate("light_sampling", "light sample's weight", text, err, 0, value={"factor": k},
                     change=(k - 1.0) * x, gain=True)]
    quarter = _quadrant(fit, inputs, x)
    return out + ([quarter] if quarter is not None else [])


light_sampling.name, light_sampling.prepare = "light_sampling", _prepare
