"""``mcrt mitsuba-suite``: mcrt's test on Mitsuba 3's own render-test suite, beside Mitsuba's.

For every scene of a Mitsuba-style ``tests/scenes`` folder that has its
reference pair (``refs/<name>_ref_rgb.exr`` and ``_var.exr``):

* a correct render at Mitsuba's budget (2e6 samples over the image, scaled
  by ``--spp-scale``), as Mitsuba renders it
  (:func:`mcrt.mitsuba_scene.render_with_variance`, in CIE XYZ, the space of
  Mitsuba's test and of the references' exact variance);
* mcrt's verdict against the reference: the multi-scale tile test
  (:func:`mcrt.stats.compare_multiscale`, variance floored at the
  reference's), noiseless differences apart; beside it Mitsuba's own
  per-pixel z-rule on the same render (:mod:`.zrule`);
* power: the stated perturbations of :mod:`.perturb` and its ladder of
  subtler sizes, rendered at the same budget and tested both ways;
* the false alarms over the correct renders, at the suite's level (one
  family-wise error rate over all scenes, Bonferroni) and, from the renders'
  family p-values, at other levels.

Modules: :mod:`.scenes` (finding the scenes; the held-out part),
:mod:`.zrule` (Mitsuba's test), :mod:`.perturb` (the perturbations),
:mod:`.run` (the computation), :mod:`.markdown` (the report),
:mod:`.cli` (the command).
"""

from mcrt.msuite.cli import register

__all__ = ["register"]
