"""The consoles every command prints to (results on stdout, progress and errors on
stderr), how names print (:func:`visible`, :func:`escape`) and the one cell format of
plain tables.

rich.progress is imported where a progress bar is shown (not every command has one)."""

from __future__ import annotations

import contextlib
import io
import os
import sys
from collections.abc import Callable, Iterator
from typing import Any, NoReturn

from rich.console import Console
from rich.markup import escape as markup_escape
from rich.text import Text

from camopt.errors import CamoptError


def visible(text: object) -> str:
    """``text`` as camopt prints it: printable characters as they are, every other one
    (control characters such as ESC, CR, LF and tab, bidirectional overrides such as
    U+202E, zero-width and other invisible characters) as its Python escape (``\\x1b``,
    ``\\n``, ``\\u202e``). A name can then neither send a terminal an escape sequence nor
    break a line; the exact text is in ``--format json`` (docs/reliability.md)."""
    text = str(text)
    if text.isprintable():
        return text
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


# rich's markup.escape is not exact: a backslash before '[' that starts no tag is
# dropped ('t\[x' printed 't[x'), and one at the end of a name is doubled unless a tag
# follows. camopt's escape instead puts private-use stand-ins for '[' and '\' (which
# visible() never lets through) that markup cannot read; the consoles turn them back.
_STAND_INS = {ord("["): "\ue000", ord("\\"): "\ue001"}
_BACK = {ord(v): chr(k) for k, v in _STAND_INS.items()}


def escape(text: object) -> str:
    """``text`` (a name: a path, a run, metric or requirement name) for markup printed by
    :data:`out` or :data:`err`: exactly as :func:`visible` shows it, whatever markup is
    around it."""
    return visible(text).translate(_STAND_INS)


def reader_left(fd: int) -> NoReturn:
    """The reader of a pipe on file descriptor ``fd`` has left (``camopt show RUN | head
    -1``): the rest of the output goes to /dev/null and camopt exits 0 without a word,
    as a Unix filter does (rich's console and typer would exit 1)."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, fd)
    os.close(devnull)
    raise SystemExit(0)


class NameConsole(Console):
    """A rich console that prints what :func:`escape` made of a name as the name; a closed
    pipe on stdout ends camopt with exit 0 (:func:`reader_left`), one on stderr sends the
    rest of stderr's messages nowhere while the command goes on (a run whose progress
    reader left still finishes and writes its archive)."""

    def on_broken_pipe(self) -> None:
        self.quiet = True
        try:
            fd = self.file.fileno()
        except (AttributeError, OSError, ValueError):  # not a real file (a test's capture)
            fd = None
        if self.stderr:
            if fd is not None:
                devnull = os.open(os.devnull, os.O_WRONLY)
                os.dup2(devnull, fd)
                os.close(devnull)
            return
        if fd is None:
            raise SystemExit(0)
        reader_left(fd)

    def render_str(self, text: str, **options: Any) -> Text:
        if not any(chr(k) in text for k in _BACK):
            return super().render_str(text, **options)
        highlighter = options.pop("highlighter", None) or self.highlighter
        rich_text = super().render_str(
            text, highlighter=lambda s: highlighter(str(s).translate(_BACK)), **options)
        rich_text.plain = rich_text.plain.translate(_BACK)  # same length: styles stay
        return rich_text


# no emoji codes: rich would print a path such as ':smile:.toml' as an emoji (what
# camopt prints is file names, quantities and markup it escapes, never an emoji)
out = NameConsole(emoji=False)
err = NameConsole(stderr=True, emoji=False)


@contextlib.contextmanager
def rows_bar(label: str, quiet: bool) -> Iterator[Callable[[int, int], None] | None]:
    """A rich progress bar on stderr over rows evaluated (``camopt.core.batch.RowsDone``:
    rows done, rows in all), or None with ``--quiet`` or when stderr is not a terminal
    (a pipe or a log file gets no bar)."""
    if quiet or not err.is_terminal:
        yield None
        return
    from rich import progress as rp

    with rp.Progress(rp.TextColumn(markup_escape(label)), rp.BarColumn(), rp.MofNCompleteColumn(),
                  rp.TimeElapsedColumn(), rp.TimeRemainingColumn(), console=err,
                  transient=True) as bar:
        task = bar.add_task(label, total=None)

        def rows_done(done: int, total: int) -> None:
            bar.update(task, total=total, completed=done)

        yield rows_done


def fmt(value: Any) -> str:
    """A table cell: floats to 6 significant digits, lists comma-joined, None as '-'."""
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, list):
        return ",".join(fmt(v) for v in value)
    return "-" if value is None else escape(str(value))  # labels may hold [markup]


def plain(value: Any) -> str:
    """:func:`fmt` without markup escaping (the layout escapes)."""
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, list):
        return ",".join(plain(v) for v in value)
    return "-" if value is None else str(value)



class OutputError(CamoptError):
    """Standard output could not take what a command printed (a full disk, a file-size
    limit, an I/O error): the output is incomplete."""


class CheckedOutput(io.RawIOBase):
    """File descriptor ``fd`` as a raw stream whose every write is whole or an
    :class:`OutputError`. Python's own stdout let a short write pass silently: under
    ``ulimit -f`` ``show --format json`` exited 0 with its output cut at 1,024 bytes.
    On a failure the descriptor is pointed at /dev/null first, so the rest of the
    output (flushed again at exit) goes nowhere instead of adding a second error; a
    closed pipe (``camopt show RUN | head -1``) is no error: exit 0, from wherever the
    write was (:func:`reader_left`; a BrokenPipeError would reach typer, which exits 1,
    or a command's ``errors()``, which calls it a bug)."""

    def __init__(self, fd: int, name: str) -> None:
        super().__init__()
        self.fd, self.name = fd, name

    def writable(self) -> bool:
        return True

    def fileno(self) -> int:
        return self.fd

    def isatty(self) -> bool:
        return os.isatty(self.fd)

    def write(self, data: Any) -> int:
        view = memoryview(data).cast("B")
        done = 0
        while done < len(view):
            try:
                n = os.write(self.fd, view[done:])
            except BrokenPipeError:
                reader_left(self.fd)
            except OSError as exc:
                self._discard()
                raise OutputError(f"{self.name}: write: {exc.strerror or exc}; the output "
                                  f"is incomplete ({done} of {len(view)} bytes of the last "
                                  "write went out)") from None
            if n <= 0:  # a write that makes no progress would loop for ever
                self._discard()
                raise OutputError(f"{self.name}: write: no bytes written; the output is "
                                  "incomplete")
            done += n
        return done

    def _discard(self) -> None:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, self.fd)
        os.close(devnull)


def checked_stdout() -> None:
    """Replace ``sys.stdout`` by a text stream over :class:`CheckedOutput` with the same
    encoding and buffering (line-buffered on a terminal): every print is then either
    written whole or an :class:`OutputError`."""
    old = sys.stdout
    try:
        fd = old.fileno()
    except (AttributeError, OSError, ValueError):  # not a real file (a test's capture)
        return
    old.flush()
    sys.stdout = io.TextIOWrapper(
        io.BufferedWriter(CheckedOutput(fd, "<stdout>")), encoding=old.encoding,
        errors=old.errors, line_buffering=bool(getattr(old, "line_buffering", False)))
