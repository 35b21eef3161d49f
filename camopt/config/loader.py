"""Read a case file, apply ``--set`` overrides, validate; every failure names file and key."""

from __future__ import annotations

import errno
import os
import re
import stat
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ValidationError

from camopt.config.models import (
    PLAUSIBILITY_KEY,
    CaseConfig,
    RobustSection,
    RunSection,
    SolverOptions,
)
from camopt.config.raw import RawDoc
from camopt.errors import ConfigError, did_you_mean

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

SECTIONS = ("case", "solver", "run", "robust")
EXTENDS = "extends"
# a bare word taken as a string: names and paths (runs/run-1.h5, /tmp/a.h5, ~/x.h5)
_BARE_WORD = re.compile(r"^[A-Za-z_./~][\w./~\-+:]*$")
# a case file is a few kB; 1 MiB leaves room for long evaluate tables and stops
# /dev/zero-like inputs before they fill memory
MAX_FILE_BYTES = 2**20
# extends chains in practice are one or two files deep
MAX_EXTENDS_DEPTH = 16


@dataclass(frozen=True)
class Base:
    """A case file another extends: its path, the keys it sets itself (``own``, without
    ``extends``) and its data with its own bases merged in (``merged``)."""

    path: str
    own: RawDoc = field(repr=False)
    merged: RawDoc = field(repr=False)


@dataclass(frozen=True)
class LoadedConfig:
    """A validated case file: the exact text read, overrides, and the parsed sections."""

    path: str
    text: str
    overrides: tuple[str, ...]
    case: CaseConfig
    solver: SolverOptions
    run: RunSection
    data: RawDoc = field(repr=False)
    robust: RobustSection | None = None
    """``[robust]`` when the case file has one: the search optimises for yield."""
    bases: tuple[Base, ...] = field(default=(), repr=False)
    """The files this one ``extends``, nearest first (empty without ``extends``)."""

    def effective(self) -> RawDoc:
        """The parsed values after overrides, as plain TOML-able data."""
        return {
            "case": self.case.model_dump(mode="json"),
            "solver": self.solver.model_dump(mode="json"),
            "run": self.run.model_dump(mode="json", exclude_none=True),
            **({"robust": self.robust.model_dump(mode="json")} if self.robust else {}),
        }

    def inherited(self, section: str, key: str) -> Base | None:
        """The base file that sets ``section.key`` when this file (and ``--set``) does not;
        None when the key is set here, by ``--set``, or nowhere."""
        overridden = {k.partition("=")[0].strip() for k in self.overrides}
        if f"{section}.{key}" in overridden or not self.bases:
            return None
        own = _own(self.text)
        if key in (own.get(section) or {}):
            return None
        for base in self.bases:
            if key in (base.own.get(section) or {}):
                return base
        return None


def parse_overrides(items: Sequence[str]) -> list[tuple[str, Any]]:
    """Parse ``key=value`` strings; the value is TOML, or a bare word taken as a string."""
    parsed = []
    for item in items:
        key, sep, raw = item.partition("=")
        key = key.strip()
        if not sep or not key or not re.fullmatch(r"[A-Za-z_][\w]*(\.[A-Za-z_]\w*)+", key):
            raise ConfigError("--set", item, "expected section.key=value, e.g. run.seed=3")
        try:
            parsed.append((key, parse_value(raw)))
        except ValueError:
            raise ConfigError("--set", key, f"cannot parse value {raw.strip()!r}") from None
    return parsed


def parse_value(raw: str) -> Any:
    """A command-line value: TOML (3, 1.5, true, [1, 2], {a = 1}, "text"), or a bare
    word or path taken as a string; ValueError otherwise."""
    raw = raw.strip()
    try:
        return tomllib.loads(f"v = {raw}")["v"]
    except RecursionError:  # tomllib recurses into nested arrays
        raise ValueError(raw) from None
    except tomllib.TOMLDecodeError:
        if not _BARE_WORD.fullmatch(raw):
            raise ValueError(raw) from None
        return raw


def apply_override(data: RawDoc, key: str, value: Any) -> None:
    """Set ``section.key`` in parsed case-file data."""
    parts = key.split(".")
    node = data
    for part in parts[:-1]:
        child = node.setdefault(part, {})
        if not isinstance(child, dict):
            raise ConfigError("--set", key, f"'{part}' is not a table")
        node = child
    node[parts[-1]] = value


def read_regular_file(path: str | Path, key: str, limit: int, what: str,
                      follow: bool = True) -> bytes:
    """The bytes of ``path``, refused as a ConfigError ``<path>: <key>: <why>`` unless it
    is a regular file of at most ``limit`` bytes (``what`` names it: 'a case file'). Every
    file camopt reads as input goes through here (case files, curves and cam points,
    a sweep's journal and lock): opened ``O_NONBLOCK`` (a FIFO must not wait for a
    writer) and checked with ``fstat`` on the opened descriptor before a byte is read (a
    device such as /dev/zero never ends; a directory is no file), then read at most
    ``limit + 1`` bytes (a file that grew since ``fstat`` is still refused). ``follow``
    False: a symbolic link is refused too (``O_NOFOLLOW``: files camopt itself keeps
    beside an archive, where a planted link would redirect the read)."""
    source = str(path)
    flags = os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC | (0 if follow else os.O_NOFOLLOW)
    try:
        fd = os.open(path, flags)
    except FileNotFoundError:
        raise ConfigError(source, key, "no such file") from None
    except IsADirectoryError:
        raise ConfigError(source, key, f"is a directory, not {what}") from None
    except (OSError, ValueError) as exc:
        if isinstance(exc, OSError) and exc.errno == errno.ELOOP and not follow:
            raise ConfigError(source, key, "cannot read (a symbolic link)") from None
        why = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        raise ConfigError(source, key, f"cannot open: {why}") from None
    try:
        info = os.fstat(fd)
        if stat.S_ISDIR(info.st_mode):
            raise ConfigError(source, key, f"is a directory, not {what}")
        if not stat.S_ISREG(info.st_mode):
            raise ConfigError(source, key, "not a regular file (a device, FIFO or socket)")
        if info.st_size > limit:
            raise ConfigError(source, key, f"{info.st_size} bytes; {what} is at most "
                              f"{limit} bytes")
        with os.fdopen(fd, "rb", closefd=False) as fh:
            raw = fh.read(limit + 1)
    except OSError as exc:
        raise ConfigError(source, key, f"cannot read: {exc.strerror or exc}") from None
    finally:
        os.close(fd)
    if len(raw) > limit:
        raise ConfigError(source, key, f"{what} is at most {limit} bytes")
    return raw


def _read(path: Path) -> tuple[str, RawDoc]:
    """A case file's text and parsed TOML (:func:`read_regular_file`, at most
    MAX_FILE_BYTES)."""
    source = str(path)
    raw = read_regular_file(path, "file", MAX_FILE_BYTES, "a case file")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigError(source, "file", f"not UTF-8 text (byte {exc.start})") from None
    try:
        return text, tomllib.loads(text)
    except RecursionError:
        raise ConfigError(source, "syntax", "values nested too deeply") from None
    except tomllib.TOMLDecodeError as exc:
        message = str(exc)
        match = re.search(r"\(at line (\d+), column (\d+)\)", message)
        where = f"line {match.group(1)}" if match else "syntax"
        what = re.sub(r"\s*\(at line \d+, column \d+\)", "", message)
        raise ConfigError(source, where, f"TOML syntax error: {what}") from None


def _validate(
    model: type[BaseModel], data: Any, section: str, source: str, overridden: set[str],
    context: RawDoc | None = None, origin: str = "--set",
) -> Any:
    try:
        return model.model_validate(data, context=context)
    except ValidationError as exc:
        error = exc.errors()[0]
        loc = ".".join(str(p) for p in (section, *error["loc"]))
        if error["type"] == "extra_forbidden":
            what = "unknown key" + did_you_mean(str(error["loc"][-1]),
                                                _keys_at(model, error["loc"][:-1]))
        elif error["type"] == "missing":
            what = "missing required key"
        else:
            what = error["msg"].removeprefix("Value error, ")
            shown = repr(error.get("input"))
            # the value that failed, when it is one value (a whole table is not shown)
            if ("input" in error and error["type"] not in ("model_type", "dict_type")
                    and not isinstance(error["input"], dict) and len(shown) <= 80):
                what += f" (got {shown})"
        blamed = any(loc == k or loc.startswith(k + ".") for k in overridden)
        raise ConfigError(origin if blamed else source, loc, what) from None


def _keys_at(model: type[BaseModel], loc: tuple[Any, ...]) -> list[str]:
    """The keys a model accepts at ``loc`` (a nested table's, following its fields' model
    types), for "did you mean"; [] where the path leaves the models."""
    for part in loc:
        field = model.model_fields.get(str(part))
        kind = field.annotation if field is not None else None
        if not (isinstance(kind, type) and issubclass(kind, BaseModel)):
            return []
        model = kind
    return [f.alias or name for name, f in model.model_fields.items()]


def _select(
    table: Any, section: str, tag: str, known: Mapping[str, Any], source: str, noun: str
) -> Any:
    if not isinstance(table, dict):
        raise ConfigError(source, section, f"[{section}] must be a table")
    value = table.get(tag)
    if isinstance(value, str) and value in known:  # a registry imports only what defines it
        return known[value]
    names = ", ".join(sorted(known))  # listing the names imports every case or solver
    if value is None:
        raise ConfigError(source, f"{section}.{tag}", f"missing; known {noun}s: {names}")
    if not isinstance(value, str):
        raise ConfigError(source, f"{section}.{tag}", f"must be a string; known {noun}s: "
                          f"{names}")
    raise ConfigError(source, f"{section}.{tag}", f"unknown {noun} {value!r}"
                      f"{did_you_mean(value, known)}; known: {names}")


def _merge(base: RawDoc, child: RawDoc) -> RawDoc:
    """[case], [run] and [robust] merge key by key; so does a child's [solver] that names
    no solver (``population = 100`` alone changes the base solver's population). A child's
    [solver] with a ``name`` replaces the base's whole, even for the same solver: a child
    that names its solver says which options it wants (fast_switch_robust.toml leaves out
    fast_switch_de.toml's [solver.polish] that way)."""
    merged = dict(base)
    for key, value in child.items():
        if (isinstance(value, dict) and isinstance(base.get(key), dict)
                and (key in ("case", "run", "robust") or (key == "solver"
                                                          and "name" not in value))):
            merged[key] = {**base[key], **value}
        else:
            merged[key] = value
    return merged


def _shown(path: Path) -> str:
    """A resolved path as messages show it: relative to the working folder when inside it."""
    relative = os.path.relpath(path)
    return path.as_posix() if relative.startswith("..") else relative


def _own(text: str) -> RawDoc:
    """The keys a case file's text sets itself (its ``extends`` left out)."""
    data = tomllib.loads(text)
    data.pop(EXTENDS, None)
    return data


def _read_extended(path: Path, seen: tuple[Path, ...] = ()
                   ) -> tuple[str, RawDoc, tuple[Base, ...]]:
    """Read a case file and, through ``extends = "other.toml"``, the files it builds on
    (a chain of at most MAX_EXTENDS_DEPTH files, without loops): its text, the merged data
    and the bases, nearest first."""
    text, data = _read(path)
    base_name = data.pop(EXTENDS, None)
    if base_name is None:
        return text, data, ()
    if not isinstance(base_name, str):
        raise ConfigError(str(path), EXTENDS, "must be a path string")
    if len(seen) >= MAX_EXTENDS_DEPTH:
        raise ConfigError(str(path), EXTENDS, f"more than {MAX_EXTENDS_DEPTH} files extend "
                          "each other")
    try:
        here = path.resolve(strict=True)
        base = (path.parent / base_name).resolve(strict=True)
    except FileNotFoundError:
        raise ConfigError(str(path), EXTENDS, f"no such file {base_name}") from None
    except (OSError, RuntimeError, ValueError) as exc:  # symlink loops, NUL bytes
        raise ConfigError(str(path), EXTENDS, f"cannot follow {base_name!r}: "
                          f"{getattr(exc, 'strerror', None) or exc}") from None
    if base in seen or base == here:
        raise ConfigError(str(path), EXTENDS, f"circular: {base_name}")
    base_text, base_data, further = _read_extended(base, (*seen, here))
    layer = Base(_shown(base), _own(base_text), base_data)
    return text, _merge(base_data, data), (layer, *further)


def load_config(
    path: str | Path,
    solvers: Mapping[str, type[SolverOptions]],
    cases: Mapping[str, type[CaseConfig]],
    overrides: Sequence[str] = (),
) -> LoadedConfig:
    """Load and validate a case file; ``solvers`` maps solver names to their Options models
    and ``cases`` case kinds to their config models (the registries pass them in: the
    config layer knows no case or solver)."""
    path = Path(path)
    source = str(path)
    text, data, bases = _read_extended(path)
    parsed = parse_overrides(overrides)
    new_solver = dict(parsed).get("solver.name")
    old_solver = data.get("solver")
    if new_solver is not None and (not isinstance(old_solver, dict)
                                   or old_solver.get("name") != new_solver):
        data["solver"] = {}  # another solver: the file's options belong to the old one
    for key, value in parsed:
        if key.split(".")[0] not in SECTIONS:
            expected = ", ".join(SECTIONS)
            hint = did_you_mean(key.split(".")[0], SECTIONS)
            raise ConfigError("--set", key, f"unknown section{hint}; expected one of {expected}")
        apply_override(data, key, value)
    loaded = replace(validate_data(data, solvers, cases, source, text, tuple(overrides),
                                   {key for key, _ in parsed}), bases=bases)
    if loaded.run.next_config is not None and loaded.inherited("run", "next_config"):
        # a base's pointer to the config that requires more names this file, or its sibling
        loaded.data.get("run", {}).pop("next_config", None)
        loaded = replace(loaded, run=loaded.run.model_copy(update={"next_config": None}))
    return loaded


def validate_data(
    data: RawDoc,
    solvers: Mapping[str, type[SolverOptions]],
    cases: Mapping[str, type[CaseConfig]],
    source: str = "<data>",
    text: str = "",
    overrides: tuple[str, ...] = (),
    overridden: set[str] | None = None,
    origin: str = "--set",
) -> LoadedConfig:
    """Validate already-parsed case-file data (a sweep cell's config, for instance); an
    error in an ``overridden`` key is blamed on ``origin`` (the option that set it:
    ``--set``, ``--grid``), not on the file."""
    overridden = overridden or set()
    for key in data:
        if key not in SECTIONS:
            raise ConfigError(source, key, f"unknown key{did_you_mean(key, SECTIONS)}; "
                              f"expected {', '.join(SECTIONS)}")
    for key in ("case", "solver"):
        if key not in data:
            raise ConfigError(source, key, f"missing [{key}] table")
    case_model = _select(data["case"], "case", "kind", cases, source, "case kind")
    solver_model = _select(data["solver"], "solver", "name", solvers, source, "solver")
    run = data.get("run", {})
    plausible = not (isinstance(run, dict) and run.get(PLAUSIBILITY_KEY) is False)
    return LoadedConfig(
        path=source,
        text=text,
        overrides=overrides,
        case=_validate(case_model, data["case"], "case", source, overridden,
                       {PLAUSIBILITY_KEY: plausible}, origin),
        solver=_validate(solver_model, data["solver"], "solver", source, overridden,
                         origin=origin),
        run=_validate(RunSection, data.get("run", {}), "run", source, overridden,
                      origin=origin),
        data=data,
        robust=(None if data.get("robust") is None else
                _validate(RobustSection, data["robust"], "robust", source, overridden,
                          origin=origin)),
    )
