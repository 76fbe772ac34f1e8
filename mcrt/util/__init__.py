"""Small helpers every layer may use, one concern per module.

:mod:`.jsonsafe` (JSON-safe copies of results), :mod:`.atomic` (files
replaced whole or not at all), :mod:`.fmt` (numbers as the reports print
them), :mod:`.progress` (progress and log lines on stderr). Machine and
version records are :mod:`mcrt.provenance`.
"""
