r"""Light counted twice: a direct-lighting pass added to a path tracer that has one, or light sampling and
emitter hits both counted at every bounce (no MIS); or the direct light left out.

With :math:`D_k` mcrt's render cut at depth k (the basis's path-depth
renders, Mitsuba's convention: :math:`D_1` is the light seen directly,
:math:`D_2 - D_1` the direct light on surfaces) and R the reference, the
model images are

* direct light counted again: :math:`R + (D_2 - D_1)`;
* light counted twice at every bounce: :math:`R + (R - D_1)`, every
  path's light doubled but the light seen directly (it has no light sample);
* the direct light missing (no light sample at the first surface hit):
  :math:`R - (D_2 - D_1)`;
* the direct light missing at the surfaces seen in a mirror (no light sample
  at the vertex after a mirror bounce, a specular flag read one bounce
  late): :math:`R - m (D_3 - D_2)`, with m the pixels whose first surface is
  a mirror (there the paths of three segments are eye, mirror, surface,
  light sample);
* the direct light missing on one surface or object alone (its branch of
  the shading code never samples the light): :math:`R - m_o (D_2 - D_1)`,
  m_o the pixels whose first surface is o, the best o (a material other
  than the scene's on o looks much the same, and the words name it too);
* only the last vertex's light kept (the radiance assigned at each vertex,
  ``L = beta * direct`` for ``L +=``), the light seen directly counted (a
  path that meets the light ends there): :math:`D_1 + (R - D_{d-1})` for
  the assignment's depth d.

Neither has a free parameter: a free weight k of the added part would fit
any change of the indirect light (a path depth off by one is k = -1 %),
which is no light counted twice. Neither renders anything: the depth renders
are the basis's (:data:`mcrt.grade.explain.basis.DEPTHS`), with the basis's
seed, so that :math:`D_2 - D_1` shares its random numbers.
"""

from __future__ import annotations

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.fit import Fit


def _depth(basis, k: int) -> np.ndarray | None:
    """The basis's render cut at depth k (the base where k is the assignment's depth), None without one."""
    if k == basis.max_depth:
        return basis.base.astype(np.float64)
    img = dict(basis.nodes.get("depth", [])).get(k)
    return None if img is None else img.astype(np.float64)


def light_twice(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """The direct light counted again, the light counted twice at every bounce, the direct light missing at the first
    hit or after a mirror, only the last vertex's light kept (the module docstring)."""
    b = inputs.basis
    d1, d2 = _depth(b, 1), _depth(b, 2)
    if d1 is None or d2 is None:
        return []
    base = b.base.astype(np.float64)
    out = []
    for name, change, what in (
            ("direct light twice", d2 - d1, "the direct light (from the light to the first surface seen) counted "
             "twice (a direct-lighting pass added to a path tracer that samples the light already)"),
            ("light twice every bounce", base - d1, "the light counted twice at every bounce (light sampling and "
             "paths that hit the light both counted, with no MIS weights), all but the light seen directly")):
        out.append(Candidate("direct_twice", name, what, fit.delta(change), 0, value={"counted": 2}, change=change))
    change = d1 - d2
    out.append(Candidate("direct_missing", "direct light missing", "the direct light missing (no light sample at the "
                         "first surface the camera sees, or its shadow ray taken as blocked where it is not: a "
                         "visibility test's result inverted, or true for every ray; it is lit only by light that has "
                         "bounced)", fit.delta(change),
                         0, value={"counted": 0}, change=change))
    last = _depth(b, b.max_depth - 1)
    if last is not None and b.max_depth > 2:
        change = d1 - last
        out.append(Candidate("depth", "only the last vertex's light", "only the light of paths of the full depth kept: "
                             "the radiance assigned, not added, at each vertex (L = beta * direct for L +=), so each "
                             "path keeps the light sampled at its last vertex, and the light seen directly",
                             fit.delta(change), 0, value={"kept": "last vertex"}, change=change))
    out += _missing_on_one(fit, inputs, d2 - d1)
    lost = _after_mirror(inputs, d2)
    if lost is not None:
        out.append(Candidate("direct_missing", "direct light missing after a mirror", "the direct light missing at "
                             "the surfaces seen in the mirror (no light sample at the vertex after a mirror bounce: a "
                             "specular flag read one bounce late), the room in the mirror lit only by light that has "
                             "bounced", fit.delta(-lost), 0, value={"counted": 0, "after": "mirror"}, change=-lost))
    return out


def _missing_on_one(fit: Fit, inputs: Inputs, direct: np.ndarray) -> list[Candidate]:
    """The direct light missing on the one surface or object (of the labels, the light and the mirror aside) where
    that fits best (the module docstring); none without labels."""
    if inputs.labels is None:
        return []
    best = None
    for i, name in enumerate(inputs.label_names):
        on = inputs.labels == i
        if name in ("the light", "nothing") or "mirror" in name or not on.any():
            continue
        change = -np.where(on[..., None], direct, 0.0)
        chi = fit.delta(change)
        if best is None or chi < best[0]:
            best = (chi, name, change)
    if best is None:
        return []
    chi, name, change = best
    # A material other than the scene's (glossy, metallic) sends the light's direct light elsewhere too: on one
    # object's few pixels the image rarely tells the two apart, and the words name both.
    return [Candidate("direct_missing", "direct light missing on one surface", f"{name} lit as by light that has "
                      "bounced alone: the direct light missing on it (no light sample there: the branch of the code "
                      "that shades it never samples the light), or its material other than the scene's, which "
                      "reflects the light's direct light elsewhere", chi, 1, value={"counted": 0, "on": name},
                      change=change)]


def _after_mirror(inputs: Inputs, d2: np.ndarray) -> np.ndarray | None:
    """The direct light on the surfaces seen in a mirror (the module docstring), None without depth 3 or labels."""
    d3 = _depth(inputs.basis, 3)
    if d3 is None or inputs.labels is None:
        return None
    mirror = np.isin(inputs.labels, [i for i, n in enumerate(inputs.label_names) if "mirror" in n])
    return np.where(mirror[..., None], d3 - d2, 0.0) if mirror.any() else None


light_twice.name = "light_twice"
