"""Lines that show long work's progress, on stderr (stdout stays for results).

The progress bar of renders is :class:`mcrt.film.Progress`.
"""

from __future__ import annotations

import sys


def log(message: str, enabled: bool = True) -> None:
    """Print ``message`` on stderr at once (flushed), where ``enabled``."""
    if enabled:
        print(message, file=sys.stderr, flush=True)
