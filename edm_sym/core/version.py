"""The package version (core: every layer may read it; the package face re-exports it)."""

from __future__ import annotations

from importlib import metadata as _metadata

try:
    __version__ = _metadata.version("edm_sym")
except _metadata.PackageNotFoundError:  # running from a source tree
    __version__ = "0+unknown"

__all__ = ["__version__"]
