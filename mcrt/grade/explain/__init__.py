r"""Explaining a failing image by the parametric mistake that fits it best, in the student's terms.

The bug catalogue (:mod:`mcrt.mutants`) names estimator bugs; students also
get the scene wrong. Here a failing image S (grade resolution, as handed in
after flips only) is compared with a family of mistakes, each a model image
:math:`M_\theta` with a parameter the student can recognise:

============== ============================================ ===================================
family         model image                                  how it is made
============== ============================================ ===================================
scale          k R (one k, or one per channel: the light's  closed form
               radiance, an exposure, a white balance)
colour         k M R: channels reordered, colour lost to    closed form; weighted least
               grey, a channel zeroed, any 3x3 matrix M     squares
albedo         each surface's albedo per channel            mcrt renders at albedo 0, 1/2, 1
                                                            and the scene's, Lagrange
                                                            interpolation per channel
walls          every wall one colour (per channel)          mcrt renders of every wall at 0,
                                                            1/4, ..., 1; Lagrange per channel
reflectance    the mirror's reflectance per channel         the same with 0, 1/2 and 1
light          the light moved along x, y, z; its size; a   mcrt renders at a few offsets
               coordinate of its centre of the wrong sign
camera         field of view, rotation, pixel-centre        a 4x finer mcrt image warped by the
               offset, aspect; another camera model         pinhole homography (or the other
               (cylinder, latitude-longitude, fisheye, a    model's rays), box-filtered
               lens's radial distortion)
eye            the camera's eye moved; looking back         mcrt renders at a few offsets
object         missing, moved along x, y, z, its            mcrt renders
               coordinates read in another order, or left
               about the origin
plane          the floor or the ceiling at another height   mcrt renders at a few offsets
depth          paths cut at depth k                         mcrt renders at max depth k
emitter        the light black where seen directly          R minus the max-depth-1 image
encoding       sRGB or a power curve on the values          closed form on R
blur           a Gaussian blur of width sigma               closed form on R
catalogue      R + (E_m - E_0) for each catalogued bug      the catalogue's renders
tone_curve     a tone map, clamp or any monotone curve      closed form; isotonic regression
sample_clamp   each sample clamped at c (fireflies)         mcrt renders at c = 1/2 ... 16
falloff        a smooth fall-off, cos^k of the ray's angle  weighted least squares; a scan
resampling     rendered at 1/k the resolution and enlarged  closed form on R
material       an object rendered with the other material   mcrt renders at 0, 1/2, 1
object_size    an object's size                             mcrt renders at a few scales
surface_black  a surface black (missing, albedo 0, normals) the albedo renders at 0
light_twice    direct light, or all light, counted twice;   the path-depth renders 1 and 2
               the direct light missing
path_weight    a path's weight carried on from a hit off by the path-depth renders
               q: at one hit, or at every hit from one on
bounce         the diffuse bounce drawn or weighted wrongly mcrt renders with the trick
               (the cosine twice, half the sphere lost)     ``bounce``
light_facing   the light emitting on its other side         one mcrt render
bad_pixels     pixels (or a block) written as 0             closed form on R
============== ============================================ ===================================

Every rendered family changes the reference by what mcrt says the mistake
changes, :math:`M_\theta = R + (B_\theta - B_0)`, with :math:`B_\theta` and
the baseline :math:`B_0` rendered with the same seed (common random numbers)
by :func:`prepare_basis` into the grading cache; at grade time everything is
NumPy (:func:`explain`). Each candidate's parameter minimises, pixel by pixel
and channel by channel,

.. math::

    \chi^2(\theta) = \sum_{p,c} \frac{(S - M_\theta)^2}{V + W + (f R)^2},

with V the noise model of the bias test (the student's noise and the
reference's), W the basis renders' own noise and f = 0.2 % the floor that no
two renderers share. The share of the difference a candidate explains is
the share of the *excess* chi-square it removes,

.. math::

    e = \frac{\chi^2_0 - \chi^2(\hat\theta)}{\chi^2_0 - n},

where :math:`\chi^2(\hat\theta)` includes :math:`p \ln n` for the p
fitted parameters (the Bayesian information criterion: three albedos do not
beat a fixed bug by fitting noise), :math:`\chi^2_0` is that of the
reference itself (M = R) and n the
number of terms (what noise alone gives; the best candidate's chi^2 where
that is lower, since capped terms of heavy-tailed noise average less than
1). The best candidate is named when it explains at least :data:`NAMED` of
the difference and lowers chi^2 by at least :data:`GAIN_SIGMAS` standard
deviations of noise's (:math:`\sqrt{2n}`); otherwise the feedback
says that no candidate does and shows where the image differs. A catalogued
bug that explains nearly as much as the best (within :data:`TIE`) is named
first: several families contain a catalogued bug exactly (the mirror's
reflectance 0 is ``mirror_wrong_sign``, the sRGB curve ``gamma_output``,
depth 9 ``depth_off_by_one``).

Layout: the contract (:class:`~mcrt.grade.candidates.Candidate`,
:class:`~mcrt.grade.candidates.Explanation`) is :mod:`mcrt.grade.candidates`;
the engine :mod:`.engine`, the chi^2 :mod:`.fit`, the renders :mod:`.basis`,
the claim rule :mod:`.claim` (the grader's is :func:`mcrt.grade.adequacy.claim_rule`:
a cause is claimed only when what it leaves is noise); the families
:mod:`.scene`, :mod:`.curves`, :mod:`.camera` and :mod:`.catalogue` (the
catalogued bugs among them, and their rankings by tiles, pixels and noise),
:mod:`.colour` and :mod:`.surface_black`, and beyond the scene file
:mod:`.tonecurve`, :mod:`.sample_clamp`, :mod:`.falloff`, :mod:`.resampling`, :mod:`.objects`,
:mod:`.light_twice`, :mod:`.path_weight`, :mod:`.bounce`, :mod:`.light_facing` and :mod:`.pixels`, in the order of
:data:`FAMILIES`.
"""

from __future__ import annotations

from mcrt.grade.explain.basis import Basis, prepare_basis
from mcrt.grade.explain.claim import GAIN_SIGMAS, NAMED, share_rule
from mcrt.grade.explain.engine import explain
from mcrt.grade.explain.families import CAMERA_FAMILIES, FAMILIES, MAJOR_FAMILIES

__all__ = ["FAMILIES", "CAMERA_FAMILIES", "MAJOR_FAMILIES", "NAMED", "GAIN_SIGMAS", "Basis", "explain", "prepare_basis",
           "share_rule"]
