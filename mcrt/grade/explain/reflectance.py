r"""Every diffuse surface's reflectance off by one factor: a Lambertian BRDF's normalisation.

A Lambertian surface reflects :math:`f = \rho / \pi`; sampled by the cosine,
a path's weight is :math:`f \cos\theta / p = \rho`. A tracer that divides
by :math:`\pi` twice (in the BRDF and in the weight), forgets it, or takes
a hemisphere's pdf for the cosine's, scales every diffuse surface's
reflectance by one factor k (:math:`1/\pi`, :math:`\pi`, 2) in direct and
indirect light alike, and no surface's colour alone explains the image: the
room darkens (or brightens) more where light has bounced more.

The model image is mcrt's render with every Lambertian albedo (walls, floor,
ceiling, tetrahedron) times k, through the nodes :data:`NODES` (1: the
scene's own) by Lagrange interpolation; light transport is a polynomial in k
of the path depth's degree, and the nodes' low-order interpolant follows it
over their range, :data:`GRID`. One parameter, fitted in the student's
terms: the factor.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.fit import Fit
from mcrt.grade.explain.objects import basis_renderer
from mcrt.grade.explain.scene import lagrange
from mcrt.grade.feedback import num as _num
from mcrt.scene import Lambertian, Scene

#: Factors rendered (1 is the basis itself): from black walls to twice the reflectance.
NODES = (0.0, 0.25, 0.5, 0.75, 1.5, 2.0)
#: Factors scanned; 1/pi (divided by pi twice) lies among them.
GRID = np.unique(np.concatenate([np.linspace(0.0, 2.0, 161), [1.0 / np.pi]]))


def _scale(v, k: float) -> tuple:
    return tuple(k * x for x in v)


def scaled_reflectance(scene: Scene, k: float) -> Scene:
    """``scene`` with every Lambertian albedo (the room's faces and diffuse objects) times ``k``."""
    room = scene.room
    room = replace(room, floor_albedo=_scale(room.floor_albedo, k), ceiling_albedo=_scale(room.ceiling_albedo, k),
                   walls=tuple(replace(w, albedo=_scale(w.albedo, k)) for w in room.walls))
    objects = tuple(replace(o, material=replace(o.material, albedo=_scale(o.material.albedo, k)))
                    if isinstance(o.material, Lambertian) else o for o in scene.objects)
    return replace(scene, room=room, objects=objects)


def _prepare(a, scene: Scene, render) -> tuple[np.ndarray, np.ndarray]:
    """(nodes, images (nodes, H, W, 3)) at the basis's spp and seed."""
    img = basis_renderer(a, render)
    return np.asarray(NODES), np.stack([img(scaled_reflectance(scene, k)) for k in NODES])


def reflectance_scale(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """Every diffuse reflectance times one factor, scanned on :data:`GRID`."""
    r = inputs.basis.extra.get(reflectance_scale.name)
    if r is None:
        return []
    base = inputs.basis.base.astype(np.float64)
    nodes = np.concatenate([r[0], [1.0]])
    imgs = np.concatenate([r[1].astype(np.float64), base[None]])
    curves = np.tensordot(lagrange(GRID, nodes), imgs, axes=(1, 0)) - base[None]
    errs = [fit.delta(c) for c in curves]
    i = int(np.argmin(errs))
    k = float(GRID[i])
    how = " (1/pi: the BRDF's 1/pi applied twice)" if abs(k - 1.0 / np.pi) < 0.005 else ""
    text = (f"every diffuse surface's reflectance {_num(k)} times the scene's{how}: a Lambertian BRDF's "
            "normalisation (f = albedo / pi; a cosine-sampled path's weight is the albedo)")
    return [Candidate("reflectance_scale", "reflectance scale", text, errs[i], 1, value={"factor": k},
                      change=curves[i])]


reflectance_scale.name, reflectance_scale.prepare = "reflectance_scale", _prepare
