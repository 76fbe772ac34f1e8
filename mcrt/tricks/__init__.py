"""The lecture's efficiency tricks, as options of mcrt, measured for speed against error (``mcrt tricks``).

The tricks are options of the ``mcrt`` renderer: the estimator's in
:mod:`mcrt.options` (:data:`mcrt.options.TRICK_OPTIONS`), the whole-render
ones in :mod:`mcrt.render` (:func:`mcrt.render.render_mcrt`), which renders
with :mod:`.adaptive` (early stopping: naive and two-stage), :mod:`.aov`
(first-hit albedo and normal buffers) and :mod:`.denoise` (Intel Open Image
Denoise): renderers, one layer below the study. The study:
:mod:`.variants` (what the report compares), :mod:`.study` (the
measurements), :mod:`.light_study` (light sampling at single receivers),
:mod:`.verdicts`, :mod:`.plots`, :mod:`.report` (reports/tricks/) and
:mod:`.cli` (the command). Nothing is imported here, so ``mcrt --help``
stays fast.
"""
