"""The folder where invflame keeps what it computes once and reuses across runs."""

from __future__ import annotations

import os
from pathlib import Path


def cache_dir() -> Path:
    """Folder for cached files (absorption tables, compiled sweeps): ``$INVFLAME_CACHE`` if
    set, else ``~/.cache/invflame``. Not created here."""
    return Path(os.environ.get("INVFLAME_CACHE") or Path.home() / ".cache" / "invflame")
