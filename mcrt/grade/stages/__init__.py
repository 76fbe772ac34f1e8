"""The stages of grading one image hand-in, in order (:func:`mcrt.grade.grader.grade_submission` runs them).

1. :mod:`.intake`: the manifest, the choice of images, reading them (``readable``);
2. :mod:`.formats`: resolution, NaN and infinite pixels, negative values;
3. :mod:`.calibration`: orientation and camera, the encoding (a transfer curve);
4. :mod:`.noise`: the noise level, and the noise model the tests use;
5. :mod:`.bias`: the tile tests and the structured-error detectors, one family (on :mod:`mcrt.stats.onesample`);
6. :mod:`.exposure`: a constant factor that alone explains a failure;
7. :mod:`.explanation`: which mistake explains the difference (:mod:`mcrt.grade.explain`);

then scoring (:mod:`mcrt.grade.scoring`), the feedback text (:mod:`mcrt.grade.feedback`) and the outputs
(:mod:`mcrt.grade.outputs`). Every stage reads and writes one :class:`.state.Grading`.
"""
