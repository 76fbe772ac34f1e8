"""The lecture's efficiency tricks, as options of mcrt, measured for speed against error (``mcrt tricks``).

Modules: :mod:`.options` (the estimator's tricks as renderer options),
:mod:`.aov` (first-hit albedo and normal buffers), :mod:`.denoise` (Intel
Open Image Denoise), :mod:`.adaptive` (early stopping: naive and two-stage),
:mod:`.study` (the measurements), :mod:`.report` (reports/tricks/) and
:mod:`.cli` (the command). Nothing is imported here, so ``mcrt --help``
stays fast.
"""
