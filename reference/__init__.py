"""The project's ground truth as package data: scene files, Mitsuba references and assignments.

This folder installs as ``mcrt.data`` (pyproject.toml maps it), so a normal,
non-editable install finds the same files as a checkout:
``mcrt.scene.DATA_DIR`` is this folder in either. It holds no code.
"""
