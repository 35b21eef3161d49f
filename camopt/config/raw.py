"""The one untyped mapping camopt keeps: a TOML table or JSON object as parsed."""

from __future__ import annotations

from typing import Any

RawDoc = dict[str, Any]
"""A TOML table or JSON object as parsed: a case file before the pydantic models
(:mod:`camopt.config.models`) validate it, a sweep's spec, or the config as run read back
from an archive (``show`` reads it without the models). Typed documents camopt builds
itself are in :mod:`camopt.core.documents`."""
