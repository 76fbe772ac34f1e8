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
over their range. No free parameter: k is one of the factors a program
gets wrong (:data:`FACTORS`); a factor fitted freely would mimic any small
darkening of the room (0.99 is no BRDF's normalisation).

A tracer that multiplies the albedo in twice (in the BRDF and again in the
sample's weight) squares every reflectance instead: each colour channel
darkens by its own albedo, a saturated wall more than a grey one. The second
family is that render (every Lambertian albedo squared), with no free
parameter: a power fitted freely would mimic any small darkening of the room
(a power of 1.02 is no program's mistake). A tracer that takes the scene's
colours for what a surface absorbs (weighing a bounce by 1 - albedo) renders
every Lambertian albedo as its complement; one that normalises a colour as
it would a direction divides each albedo by its length; a parser that rounds
what it reads keeps one decimal of each; a loader that takes the linear
colours for display values puts each through a gamma of 2.2, one way or the
other; colours given in 0-255 and divided again leave every surface nearly
black. Colours kept in a program's own storage come back a little off
(RGB565's 5-6-5 bits), and colours taken for what
they are not come back far off (logits through a sigmoid; a reflectance at
normal incidence averaged with Schlick's Fresnel; 8-bit codes divided in a
rounding integer type, every channel 0 or 1). The third family on is those
renders, with no free parameter either.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.fit import Fit
from mcrt.grade.explain.basis import basis_renderer
from mcrt.grade.explain.scene import lagrange
from mcrt.grade.feedback import num as _num
from mcrt.scene import Lambertian, Scene

#: Factors rendered (1 is the basis itself): from black walls to twice the reflectance.
NODES = (0.0, 0.25, 0.5, 0.75, 1.5, 2.0)
#: The factors tried, and what each means in a tracer.
FACTORS = ((1.0 / np.pi, "1/pi: the BRDF's 1/pi applied twice"),
           (0.5 / np.pi, "1/(2 pi): the BRDF's 1/pi applied twice and a hemisphere's 1/2 once"),
           (0.5, "1/2: a factor of 2 missing (a pdf or weight off by 2)"),
           (2.0, "2: a factor of 2 too many (a pdf or weight off by 2)"))




def remapped_reflectance(scene: Scene, f) -> Scene:
    """``scene`` with every Lambertian albedo (the room's faces and diffuse objects) through f, a function of the
    colour (an array of its three channels)."""
    def g(v):
        return tuple(float(x) for x in f(np.asarray(v, np.float64)))

    room = scene.room
    room = replace(room, floor_albedo=g(room.floor_albedo), ceiling_albedo=g(room.ceiling_albedo),
                   walls=tuple(replace(w, albedo=g(w.albedo)) for w in room.walls))
    objects = tuple(replace(o, material=replace(o.material, albedo=g(o.material.albedo)))
                    if isinstance(o.material, Lambertian) else o for o in scene.objects)
    return replace(scene, room=room, objects=objects)


def scaled_reflectance(scene: Scene, k: float) -> Scene:
    """``scene`` with every Lambertian albedo times ``k``."""
    return remapped_reflectance(scene, lambda x: k * x)


def _prepare(a, scene: Scene, render) -> tuple[np.ndarray, np.ndarray]:
    """(nodes, images (nodes, H, W, 3)) at the basis's spp and seed."""
    img = basis_renderer(a, render)
    return np.asarray(NODES), np.stack([img(scaled_reflectance(scene, k)) for k in NODES])


#: The fixed remappings of every Lambertian albedo: (family, the remapping, what it is in words).
REMAPS = (("reflectance_squared", lambda x: x * x, "every diffuse surface's reflectance squared, channel by channel: "
           "the albedo multiplied in twice (in the BRDF and again in the sample's weight)"),
          ("reflectance_complement", lambda x: 1.0 - x, "every diffuse surface's reflectance 1 - albedo, channel by "
           "channel: the scene's colours taken for what a surface absorbs (a red wall cyan)"),
          ("reflectance_normalised", lambda x: x / max(float(np.linalg.norm(x)), 1e-12), "every diffuse surface's "
           "albedo divided by its length (a colour normalised as if it were a direction): every surface brighter, a "
           "grey one most"),
          # Python's round (a parser's round(a, 1)): 0.15 is 0.1499... in binary and rounds down, 0.75 to even.
          # An "energy check": a colour whose channels sum past 1 taken to reflect more than it receives.
          ("reflectance_energy", lambda x: x / max(float(np.sum(x)), 1.0), "every diffuse surface's albedo divided "
           "by the sum of its channels where that sum exceeds 1 (an energy check that takes the channels to share "
           "the energy): the grey floor and ceiling a third of theirs, the room darker"),
          ("reflectance_rounded", lambda x: np.array([round(float(v), 1) for v in x]), "every diffuse surface's "
           "albedo rounded to one decimal, channel by channel (a parser's or a format's round(a, 1))"),
          # The scene's colours are linear reflectances; a loader that treats them as display values, or as linear
          # values to be displayed, puts them through a gamma of 2.2 one way or the other.
          ("reflectance_gamma_encoded", lambda x: np.power(x, 1.0 / 2.2), "every diffuse surface's albedo "
           "gamma-encoded, channel by channel (a ** (1/2.2), as for display): the scene's linear colours converted "
           "as if they were to be shown, every surface brighter, a dark channel most"),
          # No diffuse surface reflecting: what is left is the light seen, directly and in the mirror. Colours given in
          # 0-255 and divided once more, read as 0, or an integer film (each sample under 1 truncated to 0, the
          # light's 20 kept) make that image alike; the catalogue's shadow rays always blocked is another reading.
          ("reflectance_zero", lambda x: 0.0 * x, "every diffuse surface black (its albedo 0 or nearly: colours "
           "given in 0-255 divided by 255 once more, or read as 0; or every value under 1 lost, as in a film or sum "
           "of integers that truncates each sample): only the light is seen, directly and in the mirror"),
          ("reflectance_gamma_decoded", lambda x: np.power(x, 2.2), "every diffuse surface's albedo gamma-decoded, "
           "channel by channel (a ** 2.2): the scene's linear colours taken for sRGB values and linearised, every "
           "surface darker, a dark channel most"),
          # Colours kept in a GPU buffer's 5-6-5 bits, truncated. (Bytes read back over 256 are not tried: their
          # change, a percent or so darker, is any slight darkening's, which an adaptive sampler's bias was read as.)
          ("reflectance_rgb565", lambda x: np.floor(x.astype(np.float32) * np.float32([31, 63, 31])) / [31, 63, 31],
           "every diffuse surface's albedo packed as RGB565 by truncation ((int)(r * 31), (int)(g * 63), "
           "(int)(b * 31)): every colour darker, a weak red or blue channel most"),
          # Colours taken for what they are not: logits a differentiable renderer would store, or a reflectance at
          # normal incidence (F0) averaged over the hemisphere with Schlick's Fresnel.
          ("reflectance_sigmoid", lambda x: 1.0 / (1.0 + np.exp(-x)), "every diffuse surface's albedo through a "
           "logistic sigmoid, 1 / (1 + exp(-a)) (colour parameters stored as logits, as a differentiable renderer "
           "keeps them, though the scene gives them as they are): every colour washed out towards 0.5 to 0.73"),
          ("reflectance_schlick_average", lambda x: x + (1.0 - x) / 21.0, "every diffuse surface's albedo taken "
           "for a reflectance at normal incidence and replaced by Schlick's Fresnel averaged over the hemisphere, "
           "a + (1 - a) / 21: every colour paler, a weak channel most"),
          # 8-bit codes divided in integer arithmetic that rounds (MATLAB's uint8(a * 255) / 255): 0 or 1.
          ("reflectance_integer_division", lambda x: (np.round(x * 255.0) / 255.0 >= 0.5).astype(np.float64),
           "every diffuse surface's albedo 0 or 1, channel by channel (8-bit codes divided by 255 in an integer type "
           "that rounds, as MATLAB's uint8 does: every channel from 0.5 up 1, the rest 0)"))


def _prepare_remapped(a, scene: Scene, render) -> dict[str, np.ndarray]:
    """{family: the render with every Lambertian albedo remapped (:data:`REMAPS`)}, at the basis's spp and seed."""
    img = basis_renderer(a, render)
    return {fam: img(remapped_reflectance(scene, f)) for fam, f, _ in REMAPS}


def _scan(fit: Fit, inputs: Inputs, name: str, grid: np.ndarray):
    """The best of ``grid`` through the family's nodes and the basis (at 1) by Lagrange interpolation: (value, chi^2,
    change), or None."""
    r = inputs.basis.extra.get(name)
    if r is None:
        return None
    base = inputs.basis.base.astype(np.float64)
    nodes = np.concatenate([r[0], [1.0]])
    imgs = np.concatenate([r[1].astype(np.float64), base[None]])
    curves = np.tensordot(lagrange(grid, nodes), imgs, axes=(1, 0)) - base[None]
    errs = [fit.delta(c) for c in curves]
    i = int(np.argmin(errs))
    return float(grid[i]), errs[i], curves[i]


def reflectance_remapped(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """Every diffuse reflectance through each fixed remapping of :data:`REMAPS` (the module docstring)."""
    imgs = inputs.basis.extra.get(reflectance_remapped.name) or {}
    out = []
    for fam, _, text in REMAPS:
        if fam in imgs:
            change = imgs[fam].astype(np.float64) - inputs.basis.base.astype(np.float64)
            out.append(Candidate(fam, fam.replace("_", " "), text, fit.delta(change), 0, change=change))
    return out


def reflectance_scale(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """Every diffuse reflectance times the best of :data:`FACTORS`."""
    got = _scan(fit, inputs, reflectance_scale.name, np.array([k for k, _ in FACTORS]))
    if got is None:
        return []
    k, err, change = got
    how = next(words for f, words in FACTORS if f == k)
    text = (f"every diffuse surface's reflectance {_num(k)} times the scene's ({how}): a Lambertian BRDF's "
            "normalisation (f = albedo / pi; a cosine-sampled path's weight is the albedo)")
    return [Candidate("reflectance_scale", "reflectance scale", text, err, 0, value={"factor": k}, change=change)]


reflectance_scale.name, reflectance_scale.prepare = "reflectance_scale", _prepare
reflectance_remapped.name, reflectance_remapped.prepare = "reflectance_remapped", _prepare_remapped
