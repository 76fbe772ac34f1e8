"""Why a reference cannot be used: every error names the command that rebuilds it."""

from __future__ import annotations


class ReferenceUnavailable(RuntimeError):
    """A reference that cannot be used; the message names the command that rebuilds it."""

    def __init__(self, message: str, command: str = ""):
        super().__init__(message)
        self.command = command


class MissingReference(ReferenceUnavailable):
    """No manifest entry or no file for the requested reference."""


class StaleReference(ReferenceUnavailable):
    """The reference was built for another version of the scene (scene hash changed)."""


class CorruptReference(ReferenceUnavailable):
    """The file's checksum does not match the manifest, or it does not read."""
