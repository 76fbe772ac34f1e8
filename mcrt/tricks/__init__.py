"""The lecture's efficiency tricks, as options of mcrt, measured for speed against error (``mcrt tricks``).

Modules: :mod:`.options` (the tricks as renderer options) and :mod:`.render`
(the ``mcrt`` renderer with the whole-render tricks), :mod:`.adaptive`
(early stopping: naive and two-stage), :mod:`.aov` (first-hit albedo and
normal buffers) and :mod:`.denoise` (Intel Open Image Denoise);
:mod:`.variants` (what the report compares), :mod:`.study` (the
measurements), :mod:`.light_study` (light sampling at single receivers),
:mod:`.verdicts`, :mod:`.plots`, :mod:`.report` (reports/tricks/) and
:mod:`.cli` (the command). Nothing is imported here, so ``mcrt --help``
stays fast.
"""
