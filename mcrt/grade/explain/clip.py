r"""Everything beyond a distance from the eye missing: a far clip plane, or a largest ray distance set too small.

A rasteriser's far plane (a camera's far clip) cuts what lies beyond a depth
along the view axis; a ray tracer's largest distance (t_max left at a
default, a shadow ray's bound kept for the camera's rays) cuts along each
ray. Either leaves black where the camera's rays would meet something
farther, and the rest of the image as it was. The model is
:math:`R\,f_t`, with :math:`f_t` the share of a pixel's 4 x 4 camera rays
(:mod:`mcrt.grade.hits`, prepared by :mod:`~mcrt.grade.explain.aov`) whose
first hit is nearer than t, for both measures of distance; t is scanned over
the distances the camera's rays reach (one parameter). A bound on every ray,
the bounces' too, also darkens what is left (light that travels farther than
t between surfaces is lost), which this model leaves to the remainder.
"""

from __future__ import annotations

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.fit import Fit
from mcrt.grade.feedback import num as _num

#: The distances scanned: quantiles of the camera rays' hits (the nearest and farthest few per cent left out: a cut
#: there changes a handful of pixels, which the tiles' noise cannot tell from none), refined between the best's
#: neighbours.
QUANTILES = np.linspace(0.03, 0.97, 95)
REFINE = 24

#: Each measure's words: the distance's name and what cuts there.
MEASURES = {"ray_depth": ("along the view axis", "a far clip plane at {t} (a rasteriser's far plane, or a camera's "
                          "far_clip)"),
            "ray_distance": ("along each ray", "the rays' largest distance t_max = {t} (a default left in the ray, "
                             "or a shadow ray's bound kept for every ray)")}


def clip(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """Everything beyond t black, t scanned along the view axis and along the rays (the module docstring)."""
    hits = inputs.basis.extra.get("aov") if inputs.basis is not None else None
    if hits is None or "ray_depth" not in hits or hits["ray_depth"].shape[:2] != fit.R.shape[:2]:
        return []
    out = []
    for key, (along, what) in MEASURES.items():
        depth = hits[key]
        reach = depth[np.isfinite(depth)]
        if reach.size == 0:
            continue
        grid = np.unique(np.quantile(reach, QUANTILES))
        errs = [fit.delta(_change(fit, depth, t)) for t in grid]
        i = int(np.argmin(errs))
        fine = np.linspace(grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)], REFINE)
        errs = [fit.delta(_change(fit, depth, t)) for t in fine]
        t = float(fine[int(np.argmin(errs))])
        change = _change(fit, depth, t)
        shown = _num(round(t, 1))
        out.append(Candidate("far_clip", f"far clip {along}", f"everything farther than {shown} from the eye "
                             f"{along} missing, black: {what.format(t=shown)}", min(errs), 1,
                             value={"measure": along, "distance": round(t, 2)}, change=change))
    return out


def _change(fit: Fit, depth: np.ndarray, t: float) -> np.ndarray:
    """-R where the pixel's rays reach beyond t, in proportion to how many do."""
    beyond = np.mean(~(depth < t), axis=-1)
    return -fit.R * beyond[..., None]


clip.name = "far_clip"
