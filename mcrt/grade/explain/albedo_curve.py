r"""Every colour of the scene through one rule: each distinct value the scene's colours take replaced by one value.

A program that reads, stores or converts the scene's colours by one rule (a
byte format, a colour space's transfer function, a parameter taken for
something else) changes every channel of every surface by the same function
of its value: the 0.15 of three walls' weak channels alike, whatever wall.
The rules a program is known to apply are rendered exactly
(:mod:`.reflectance`); this family fits the rule itself, one parameter per
distinct value (eleven in the course's scene), and so names a rule no one
listed in the student's terms ("0.15 read as 0.19").

The model is the sum of each surface's albedo curve (the Lagrange
polynomial through its renders, as in :func:`.scene.albedos`), which leaves
out what two changed surfaces do to each other (second order in the
changes). The fit is a coordinate descent over the values (:data:`SWEEPS`
sweeps on a grid of 101 in [0, 1] refined by a parabola, pixel chi^2 with
the fit's weights); for each value every surface and channel that holds it
moves together, which the chi^2 of the three channels weighs at once. The
rule is fitted monotone (each value between its neighbours'): a program's
rule keeps the order of what it maps, while a change of the light that
moves light between surfaces would fit as values up here and down there.
Values moved both ways, none by
:data:`~mcrt.grade.explain.scene.TYPED` or more, are what a mistake in how
light bounces makes (:func:`.scene.albedos`' rule): no candidate. It is
flexible (:attr:`~mcrt.grade.candidates.Candidate.flexible`): claimed only
where its remainder is noise and no other candidate's is.
"""

from __future__ import annotations

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.fit import Fit, refine
from mcrt.grade.explain.scene import TYPED, lagrange, surface_curve
from mcrt.grade.feedback import num as _num

#: Sweeps of the coordinate descent over the values.
SWEEPS = 4
#: A value counts as moved in the words when it moves by more than this, and the family is a candidate only where
#: a value two surfaces or more hold does: a rule that moves no colour by a few hundredths is no rule a program
#: applies to its colours, and one that moves a colour only one surface holds is that surface's colour (the albedo
#: family's reading, which a change of that object's shape also takes up in part).
MOVED = 0.03


def _members(b) -> dict[float, list[tuple[str, int]]]:
    """{value: [(surface label, channel)]} over the albedo basis's surfaces: which colours hold each value."""
    out: dict[float, list[tuple[str, int]]] = {}
    for lab, (_, _, scene_v) in b.albedo.items():
        for c, v in enumerate(scene_v):
            out.setdefault(round(float(v), 4), []).append((lab, c))
    return dict(sorted(out.items()))


def _channel_terms(fit: Fit, b, c: int, labels: list[str]):
    """For channel c: each surface's nodes, the offsets of its coefficients, the Gram matrix of every surface's
    renders minus the basis (weighted by the fit's pixel weights) and their projections on the difference."""
    w = np.where(fit.ok[..., c], fit.w[..., c], 0.0)
    nodes, ys, at = {}, [], {}
    for lab in labels:
        nodes[lab], y = surface_curve(b, lab, c)
        at[lab] = sum(len(nodes[k]) for k in nodes) - len(nodes[lab])
        ys.append(y)
    Y = np.concatenate(ys)
    return nodes, at, Y, np.einsum("jhw,khw,hw->jk", Y, Y, w), np.einsum("jhw,hw->j", Y, fit.D[..., c] * w)


def _holders(held: list[tuple[str, int]]) -> str:
    """Which colours hold a value, in words: "wall DE's green", "the floor", "5 surfaces"."""
    by: dict[str, list[int]] = {}
    for lab, c in held:
        by.setdefault(lab, []).append(c)
    if len(by) > 2:
        return f"{len(by)} surfaces"
    names = ("red", "green", "blue")
    return " and ".join(lab if len(cs) == 3 else f"{lab}'s {' and '.join(names[c] for c in cs)}"
                        for lab, cs in by.items())


def albedo_curve(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """Every colour of the scene through one fitted rule (the module docstring)."""
    b = inputs.basis
    members = _members(b)
    if len(members) < 2:
        return []
    labels = list(b.albedo)
    terms = [_channel_terms(fit, b, c, labels) for c in range(3)]
    # Each channel's coefficients (Lagrange weights of every surface's nodes), at the scene's values to start.
    coef = [np.zeros(len(t[3])) for t in terms]
    for c, (nodes, at, _, _, _) in enumerate(terms):
        for lab in labels:
            coef[c][at[lab] + len(nodes[lab]) - 1] = 1.0  # the scene's value is each surface's last node
    grid = np.linspace(0.0, 1.0, 101)
    fitted = {v: v for v in members}
    values = list(members)
    for sweep in range(SWEEPS):
        # Up the values, then down: a rule that moves every value one way needs each value's neighbour moved first.
        for i in (range(len(values)) if sweep % 2 == 0 else range(len(values) - 1, -1, -1)):
            v, held = values[i], members[values[i]]
            lo = fitted[values[i - 1]] if i > 0 else 0.0
            hi = fitted[values[i + 1]] if i + 1 < len(values) else 1.0
            err = np.zeros(len(grid))
            for c, (nodes, at, _, gram, proj) in enumerate(terms):
                mine = [lab for lab, ch in held if ch == c]
                if not mine:
                    continue
                C = np.repeat(coef[c][None], len(grid), axis=0)
                for lab in mine:
                    C[:, at[lab]:at[lab] + len(nodes[lab])] = lagrange(grid, nodes[lab])
                err += -2 * C @ proj + np.einsum("gj,jk,gk->g", C, gram, C)
            err[(grid < lo - 1e-9) | (grid > hi + 1e-9)] = np.inf  # monotone: between its neighbours' values
            j = int(np.argmin(err))
            x = refine(grid, err, j) if np.isfinite(err[max(j - 1, 0):j + 2]).all() else grid[j]
            fitted[v] = float(np.clip(x, lo, hi))
            for c, (nodes, at, _, _, _) in enumerate(terms):
                for lab in (lab for lab, ch in held if ch == c):
                    coef[c][at[lab]:at[lab] + len(nodes[lab])] = lagrange(np.array([fitted[v]]), nodes[lab])[0]
    moved = {v: fitted[v] - v for v in members if abs(fitted[v] - v) > MOVED}
    if not any(len({lab for lab, _ in members[v]}) > 1 for v in moved):
        return []  # no value two surfaces hold moved: one surface's colour, the albedo family's reading
    if len({np.sign(d) for d in moved.values()}) > 1 and max(abs(d) for d in moved.values()) < TYPED:
        return []  # a few hundredths up here and down there: light moved between surfaces (scene.albedos' rule)
    dm = np.stack([np.tensordot(coef[c], t[2], axes=(0, 0)) for c, t in enumerate(terms)], axis=-1)
    pairs = ", ".join(f"{_num(v)} ({_holders(members[v])}) as {fitted[v]:.2f}" for v in members if v in moved)
    ways = {np.sign(d) for d in moved.values()}
    how = ("every such colour brighter" if ways == {1.0} else "every such colour darker" if ways == {-1.0}
           else "some colours brighter, others darker")
    text = (f"every colour of the scene through one rule, whatever the surface: {pairs} ({how}; a rule on how the "
            "colours are read, stored or converted: check the code between the scene's numbers and the albedo a "
            "bounce uses)")
    return [Candidate("albedo_curve", "every colour through one rule", text, fit.delta(dm), len(members),
                      value={_num(v): round(fitted[v], 3) for v in members}, change=dm, flexible=True)]


albedo_curve.name = "albedo_curve"
