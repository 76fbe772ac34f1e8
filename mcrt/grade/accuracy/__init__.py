"""How well grading judges a class of realistic hand-ins: the class, the run, the report, the command.

* :mod:`~mcrt.grade.accuracy.cases`: the class. Wrong renders are Mitsuba
  renders of the scene edited the way a student's tracer goes wrong (camera,
  geometry, materials, light, post-processing, encoding, path depth), never
  mcrt's catalogued mutants; correct renders come from several estimators and
  samplers at the course's range of spp and in the file encodings students use.
* :mod:`~mcrt.grade.accuracy.outside` and :mod:`~mcrt.grade.accuracy.programs`:
  two more classes, mistakes outside the scene file and mistakes of students'
  programs (the latter written apart from the grader's rules);
  :mod:`~mcrt.grade.accuracy.fresh`, a fourth (held out until first graded): mistakes no
  other class tried, also written apart from the grader's rules.
* :mod:`~mcrt.grade.accuracy.run`: every case graded with the course
  assignment; score, points lost, and whether the feedback named the cause.
* :mod:`~mcrt.grade.accuracy.markdown` and :mod:`~mcrt.grade.accuracy.cli`:
  the report (reports/grading_accuracy/) and ``mcrt grade-accuracy``.
"""
