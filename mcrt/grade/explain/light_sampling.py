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
(:func:`factors`: the light's area A or 1/A, 2 or 1/2, pi or 1/pi (a
radiance confused with an exitance), the number of shadow rays a point sums
where their mean belongs); a weight fitted
freely would mimic any small change of the light on the room (an adaptive
sampler's bias of -1 % is no light sample's weight of 0.99).

A light sample drawn on part of the light with the whole light's pdf (its
coordinates in [0, 1) where [-1, 1) was meant: one quadrant) sheds the
light's power from that part alone: the light on surfaces is that of the
quadrant at 4 times the radiance, :math:`B_q - D_{1,q}` (mcrt renders of
the scene with the light replaced by the brighter quadrant, full and cut at
depth 1), the light seen directly unchanged. Each quadrant is a candidate
with no free parameter.

More generally a light sample drawn uniformly over a rectangle :math:`Q` of
the light's plane (a corner taken for the centre, a side for a half-side,
a range's arguments read as offset and width) sheds, weighted by the pdf of
:math:`Q`, the light of an emitter covering :math:`Q` at the light's
radiance; weighted by the light's pdf :math:`1/A`, that of :math:`Q` at
:math:`A/|Q|` times it. Light on surfaces is linear in the emitter's
radiance over the plane, so with :math:`S_c` the light a cell :math:`c` of a
grid in the plane sheds (mcrt renders, the cell as the light, full minus
cut at depth 1), :math:`Q`'s is :math:`\sum_{c \in Q} S_c`, and the
change is taken against the light's own cells (their noise cancels where
:math:`Q` and the light share cells). Every rectangle of the grid's cells
and both weights are tried (:func:`_rectangle`): a discrete choice of four
edges, counted as four parameters. The light sampled so at the first
surface a camera ray meets alone (a direct-light routine of its own there)
is not a candidate: its change is a little of the direct light on the
surfaces in view, which a rectangle's fits freely (walls moved 0.1 inwards,
lit a little more, were claimed as such a rectangle).
"""

from __future__ import annotations

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.fit import Fit
from mcrt.grade.explain.light_twice import _depth
from mcrt.grade.feedback import fmt_values as _fmt
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
            (1.0 / np.pi, "1/pi: the light's radiance divided by pi in the light sample (taken for its exitance)"),
            (np.pi, "pi: the light's radiance multiplied by pi in the light sample (an exitance's factor), or the "
             "Lambertian BRDF's 1/pi left out of it (f = albedo for albedo / pi)"),
            *((float(n), f"{n}: {n} shadow rays a point summed where their mean belongs") for n in SHADOW_RAYS))


#: Sides of the square a light's samples may come from, as a factor of the light's (1 is the light itself).
ELSEWHERE_SIZES = (0.5, 0.75, 1.25, 1.5, 2.0)


def _elsewhere(scene):
    """(what, words, scene) with the light moved along x or y, or resized about its centre, that stays inside the
    room: where a copy of the light in the sampling code may put it."""
    from dataclasses import replace

    from mcrt.grade.explain.basis import AXES, LIGHT_OFFSETS, _light_inside, _shift

    lt = scene.light
    out = []
    for axis in (0, 1):
        for d in LIGHT_OFFSETS:
            out.append((("moved", AXES[axis], d), replace(scene, light=replace(lt, center=_shift(lt.center, axis, d)))))
    for f in ELSEWHERE_SIZES:
        out.append((("size", f), replace(scene, light=replace(lt, size=(lt.size[0] * f, lt.size[1] * f)))))
    return [(what, s) for what, s in out if _light_inside(s)]


def _quadrants(scene):
    """(name, scene) with the light replaced by each quarter of itself at 4 times its radiance (the same power)."""
    from dataclasses import replace

    lt = scene.light
    hx, hy = lt.size[0] / 4, lt.size[1] / 4
    for sx, sy in ((1, 1), (-1, 1), (-1, -1), (1, -1)):
        q = replace(lt, center=(lt.center[0] + sx * hx, lt.center[1] + sy * hy, lt.center[2]),
                    size=(lt.size[0] / 2, lt.size[1] / 2), radiance=tuple(4.0 * r for r in lt.radiance))
        yield f"{'+' if sx > 0 else '-'}x {'+' if sy > 0 else '-'}y", replace(scene, light=q)


#: Cells of the grid in the light's plane (:func:`_cells`) across each side of the light, and how far the grid
#: reaches beyond the light's edges, in light sides: a rectangle up to a side and a half off still lies on it.
CELLS_ACROSS = 4
REACH = 1.5


def _cells(scene):
    """(i, j, scene or None) for each cell of a grid of squares in the light's plane, CELLS_ACROSS across the light
    and REACH light sides beyond each of its edges: the scene with the light replaced by that cell at the light's
    radiance, None for a cell not inside the room (it lights nothing the camera sees)."""
    from dataclasses import replace

    from mcrt.grade.explain.basis import _light_inside

    lt = scene.light
    n = int(round(CELLS_ACROSS * (1 + 2 * REACH)))
    side = (lt.size[0] / CELLS_ACROSS, lt.size[1] / CELLS_ACROSS)
    x0 = lt.center[0] - lt.size[0] * (0.5 + REACH)
    y0 = lt.center[1] - lt.size[1] * (0.5 + REACH)
    for i in range(n):
        for j in range(n):
            c = replace(lt, center=(x0 + (i + 0.5) * side[0], y0 + (j + 0.5) * side[1], lt.center[2]), size=side)
            s = replace(scene, light=c)
            yield i, j, (s if _light_inside(s) else None)


def _prepare(a, scene, render) -> dict[str, np.ndarray]:
    """quadrant -> the light it sheds on surfaces (its render minus its render cut at depth 1), basis spp and seed;
    the same for every cell of :func:`_cells`."""
    from mcrt.grade.explain.basis import basis_settings

    spp, seed = basis_settings(a)

    def img(s, depth):
        return render(s, a.camera, a.grade_width, a.grade_height, depth, spp, seed).mean.astype(np.float32)

    n = int(round(CELLS_ACROSS * (1 + 2 * REACH)))
    cells = np.zeros((n, n, a.grade_height, a.grade_width, 3), np.float32)
    for i, j, s in _cells(scene):
        if s is not None:
            cells[i, j] = img(s, a.max_depth) - img(s, 1)
    return {"quarters": {name: img(s, a.max_depth) - img(s, 1) for name, s in _quadrants(scene)},
            "elsewhere": [(what, img(s, a.max_depth) - img(s, 1)) for what, s in _elsewhere(scene)],
            "cells": cells}


def _quadrant(fit: Fit, inputs: Inputs, x: np.ndarray) -> Candidate | None:
    """The best quadrant of :func:`_quadrants` as the light sampled (the module docstring), None without renders."""
    quads = (inputs.basis.extra.get(light_sampling.name) or {}).get("quarters")
    if not quads:
        return None
    err, name, change = min(((fit.delta(q - x), name, q - x) for name, q in
                             ((n, q.astype(np.float64)) for n, q in quads.items())), key=lambda t: t[0])
    text = (f"the light's samples drawn on one quarter of it (the {name} quarter) with the whole light's pdf: its "
            "light on surfaces comes from that quarter, 4 times as bright, the light itself seen right (sample "
            "coordinates drawn in [0, 1) where [-1, 1) was meant)")
    return Candidate("light_sampling", "light sampled on a quarter", text, err, 0, value={"quarter": name},
                     change=change)


def _sampled_elsewhere(fit: Fit, inputs: Inputs, x: np.ndarray) -> Candidate | None:
    """The best light as sampled of :func:`_elsewhere` (the module docstring), None without renders."""
    v = inputs.basis.values
    best = None
    for what, on in (inputs.basis.extra.get(light_sampling.name) or {}).get("elsewhere", ()):
        on = on.astype(np.float64)
        kept = (("its radiance", 1.0),) if what[0] == "moved" else (("the pdf of that square", 1.0),
                                                                     ("the whole light's pdf", 1.0 / what[1] ** 2))
        for how, c in kept:
            err = fit.delta(c * on - x)
            if best is None or err < best[0]:
                best = (err, what, how, c * on - x)
    if best is None:
        return None
    err, what, how, change = best
    if what[0] == "moved":
        from mcrt.grade.explain.basis import AXES, _shift

        axis, d = what[1], what[2]
        centre = _shift(v["light_center"], AXES.index(axis), d)
        text = (f"the light's samples drawn about {_fmt(centre, 2)} where the light is at {_fmt(v['light_center'], 2)} "
                f"(moved by {d:+g} along {axis}): its light on surfaces comes from there, the light itself seen where it "
                "is (the sampling code's own copy of the light's position typed wrong)")
        value = {"centre": centre}
    else:
        f = what[1]
        side = " x ".join(_num(f * float(x)) for x in v["light_size"])
        whole = how == "the whole light's pdf"
        power = "the light's power" if whole else f"{_num(f * f)} times the light's power"
        text = (f"the light's samples drawn on a {side} square about its centre where the light is "
                f"{' x '.join(_num(float(x)) for x in v['light_size'])}, weighted by {how} ({power} on surfaces), the "
                "light itself seen right (the sampling code's own copy of the light's side)")
        value = {"side": f, "pdf": "whole light" if whole else "sampled square"}
    return Candidate("light_sampling", "light sampled elsewhere", text, err, 0, value=value, change=change)


#: Rectangles of :func:`_rectangle` ranked by the uncapped chi^2 whose capped chi^2 is computed.
RECTANGLES_CHECKED = 8


def _rectangles(n: int):
    """(i0, j0, i1, j1) of every rectangle [i0, i1) x [j0, j1) of an n x n grid's cells, as flat arrays."""
    lo, hi = np.triu_indices(n + 1, 1)
    I0, J0 = np.meshgrid(lo, lo, indexing="ij")
    I1, J1 = np.meshgrid(hi, hi, indexing="ij")
    return I0.ravel(), J0.ravel(), I1.ravel(), J1.ravel()


def _sums(fit: Fit, cells: np.ndarray, x: np.ndarray, rects) -> tuple[np.ndarray, np.ndarray]:
    """(a'b, a'Ga) of every rectangle, whose change k S_Q - x for Q's cells leaves the uncapped chi^2
    k^2 a'Ga - 2 k a'b (less a constant): a the indicator of Q over the cells, y = D + x, and G, b the cells' Gram
    matrix and products with y, summed over rectangles by inclusion and exclusion over cumulative sums."""
    n = cells.shape[0]
    sw = np.sqrt(fit.w).ravel()
    y = (fit.D + x).ravel() * sw
    flat = cells.reshape(n * n, -1)
    lit = np.flatnonzero(np.any(flat != 0, axis=1))  # cells inside the room: the Gram matrix of those alone
    S = flat[lit].astype(np.float64) * sw
    G = np.zeros((n * n, n * n))
    G[np.ix_(lit, lit)] = S @ S.T
    b = np.zeros(n * n)
    b[lit] = S @ y
    B = np.zeros((n + 1, n + 1))
    B[1:, 1:] = b.reshape(n, n).cumsum(0).cumsum(1)
    Q = np.zeros((n + 1,) * 4)
    Q[1:, 1:, 1:, 1:] = G.reshape(n, n, n, n).cumsum(0).cumsum(1).cumsum(2).cumsum(3)
    I0, J0, I1, J1 = rects
    ab = B[I1, J1] - B[I0, J1] - B[I1, J0] + B[I0, J0]
    aga = np.zeros_like(ab)
    for si, i in ((1, I1), (-1, I0)):
        for sj, j in ((1, J1), (-1, J0)):
            for sk, k in ((1, I1), (-1, I0)):
                for sl, l in ((1, J1), (-1, J0)):
                    aga += si * sj * sk * sl * Q[i, j, k, l]
    return ab, aga


def _rectangle(fit: Fit, inputs: Inputs) -> Candidate | None:
    """The best rectangle of the grid's cells as the region the light's samples come from, weighted by its own pdf or
    the light's (the module docstring), None without cell renders.
    The change is taken against the light's own cells, not the basis's render: the cells a rectangle shares with
    the light cancel with their noise."""
    cells = (inputs.basis.extra.get(light_sampling.name) or {}).get("cells")
    if cells is None or not np.any(cells):
        return None
    v = inputs.basis.values
    n = cells.shape[0]
    size = np.asarray(v["light_size"], np.float64)
    centre = np.asarray(v["light_center"], np.float64)
    side = size / CELLS_ACROSS
    origin = centre[:2] - size * (0.5 + REACH)
    m = int(CELLS_ACROSS * REACH)
    rects = I0, J0, I1, J1 = _rectangles(n)
    area = (I1 - I0) * (J1 - J0) * side[0] * side[1]
    light = (I0 == m) & (J0 == m) & (I1 == n - m) & (J1 == n - m)
    best = None
    x = cells[m:n - m, m:n - m].sum(axis=(0, 1), dtype=np.float64)  # the light's own, as its cells shed it
    ab, aga = _sums(fit, cells, x, rects)
    for own, k in ((True, np.ones_like(area)), (False, size[0] * size[1] / area)):
        chi = k * k * aga - 2.0 * k * ab
        chi[light] = np.inf  # the light itself: no change
        for r in np.argsort(chi)[:RECTANGLES_CHECKED]:
            change = k[r] * cells[I0[r]:I1[r], J0[r]:J1[r]].sum(axis=(0, 1), dtype=np.float64) - x
            err = fit.delta(change)
            if best is None or err < best[0]:
                best = (err, r, own, float(k[r]), change)
    err, r, own, k, change = best
    lo_xy = origin + side * np.array([I0[r], J0[r]])
    hi_xy = origin + side * np.array([I1[r], J1[r]])
    span = " x ".join(f"[{_num(float(a))}, {_num(float(c))}]" for a, c in zip(lo_xy, hi_xy))
    where = " x ".join(f"[{_num(float(a))}, {_num(float(c))}]" for a, c in zip(centre[:2] - size / 2,
                                                                               centre[:2] + size / 2))
    how = "the pdf of that rectangle" if own else "the light's pdf"
    power = "its radiance" if own else f"{_num(k)} times its radiance"
    text = (f"the light's samples drawn over x, y in {span} where the light covers {where}, weighted by {how}: "
            f"its light on surfaces comes from that rectangle at {power}, the light itself seen right (the light "
            "sample's corner, side or range wrong in the sampling code)")
    value = {"x": (float(lo_xy[0]), float(hi_xy[0])), "y": (float(lo_xy[1]), float(hi_xy[1])),
             "pdf": "rectangle" if own else "whole light"}
    # More light on surfaces with the light seen right is also what counting the light twice (its light sample and
    # the paths that hit it) does: a rectangle about the light fits it nearly as well, and is no other cause for it.
    return Candidate("light_sampling", "light sampled over a rectangle", text, err, 4, value=value, change=change,
                     generalises=("direct_twice",))


def light_sampling(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """The light on surfaces k times the truth for the best k of :func:`factors`, from the best quarter of the
    light (:func:`_quadrant`) and from the best light as sampled elsewhere (:func:`_sampled_elsewhere`), the light
    seen directly unchanged (the module docstring)."""
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
    return out + [c for c in (_quadrant(fit, inputs, x), _sampled_elsewhere(fit, inputs, x),
                               _rectangle(fit, inputs)) if c is not None]


light_sampling.name, light_sampling.prepare = "light_sampling", _prepare
