"""Writing output files safely: atomically, never over an input, appendable result logs.

Every file iterc writes goes through :func:`atomic_write_text` / :func:`atomic_write_bytes`:
the content is written to a temporary file *in the target's folder* (same file system),
flushed and ``fsync``-ed, then renamed over the target with :func:`os.replace` (atomic on
POSIX and Windows), and the folder is ``fsync``-ed so the rename survives a power cut.  A
process killed at any point leaves either the old file intact or the new one complete --
never a 0-byte or truncated file (at most a stray hidden ``.NAME.*.tmp`` temp file beside it,
named so it is easy to spot and delete).

:func:`refuse_overwrite_input` stops ``iterc compile x.lts -o x.lts`` before any work is done.
:func:`append_line` appends one complete line (a CSV row, a JSON line) with a single
``write`` on an ``O_APPEND`` descriptor and ``fsync``, so a result log grows one finished
record at a time and a killed run can resume from it.

Test hook: with the environment variable ``ITERPLAN_TEST_KILL_AT=NAME`` the process kills
itself with SIGKILL at write point NAME (``mid-write`` -- half the bytes in the temp file --,
``before-replace`` -- temp file complete, not yet renamed --, ``after-replace``,
``mid-append`` -- half a line appended --, ``after-append``); ``NAME:K`` dies at the K-th
passage.  tests/robustness/test_outputs.py shows the guarantee at every point.

Stdlib only: the runtime (which ships to the aircraft) may import this module.
"""

from __future__ import annotations

import contextlib
import os
import signal
import tempfile
from collections.abc import Iterable
from pathlib import Path

__all__ = ["OutputError", "OutputFolder", "atomic_write_text", "atomic_write_bytes",
           "atomic_write_json",
           "refuse_overwrite_input", "append_line", "complete_lines", "check_writable_dir"]

KILL_ENV = "ITERPLAN_TEST_KILL_AT"


class OutputError(Exception):
    """An output cannot be written (a user error: exit 1); ``message`` says why."""

    def __init__(self, message: str) -> None:
        super().__init__(message)
        self.message = message


_hits: dict[str, int] = {}


def _armed(name: str) -> bool:
    """True if ``ITERPLAN_TEST_KILL_AT`` asks to die at this passage of point ``name``
    (``NAME`` -- the first time --, or ``NAME:K`` -- the K-th time)."""
    want = os.environ.get(KILL_ENV)
    if not want:
        return False
    point, _, k = want.partition(":")
    if point != name:
        return False
    _hits[name] = _hits.get(name, 0) + 1
    return _hits[name] == (int(k) if k.isdigit() else 1)


def _kill_point(name: str) -> None:
    if _armed(name):
        os.kill(os.getpid(), signal.SIGKILL)


def _fsync_dir(folder: Path) -> None:
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:  # e.g. Windows: folders cannot be opened; the rename is still atomic
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def atomic_write_bytes(path: str | os.PathLike[str], data: bytes) -> None:
    """Write ``data`` to ``path`` atomically (temp file in the same folder + fsync + rename).

    The new file gets the old file's permission bits if it existed, else the usual ``0o666``
    minus the umask.  Raises :class:`OSError` as ``open`` would (no such folder, read-only...).
    """
    target = Path(path)
    folder = target.parent if str(target.parent) else Path(".")
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name[:100]}.", suffix=".tmp", dir=folder)
    try:
        try:
            mode = os.stat(target).st_mode & 0o7777
        except OSError:
            umask = os.umask(0)
            os.umask(umask)
            mode = 0o666 & ~umask
        with os.fdopen(fd, "wb") as f:
            half = len(data) // 2
            f.write(data[:half])
            if _armed("mid-write"):
                f.flush()
                os.kill(os.getpid(), signal.SIGKILL)
            f.write(data[half:])
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, mode)
        _kill_point("before-replace")
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    _fsync_dir(folder)
    _kill_point("after-replace")


def atomic_write_text(path: str | os.PathLike[str], text: str, encoding: str = "utf-8") -> None:
    """:func:`atomic_write_bytes` of ``text`` encoded (newlines written as given)."""
    atomic_write_bytes(path, text.encode(encoding))


def atomic_write_json(path: str | os.PathLike[str], obj: object, *, indent: int | None = 2
                      ) -> None:
    """Write ``obj`` as *valid* JSON (RFC 8259), atomically: NaN and Infinity, which
    ``json.dumps`` would write as the non-JSON tokens ``NaN``/``Infinity``, raise
    :class:`ValueError` before anything is written -- so no output file is ever invalid
    JSON (or GeoJSON)."""
    import json

    text = json.dumps(obj, indent=indent, allow_nan=False)
    atomic_write_text(path, text + "\n")


def append_line(path: str | os.PathLike[str], line: str, encoding: str = "utf-8") -> None:
    """Append one complete line to ``path`` (created if missing), durably.

    The line goes out in one ``write`` on an ``O_APPEND`` descriptor and is fsync-ed before
    returning.  A kill during the write can leave at most a partial *last* line, which
    :func:`complete_lines` drops when the file is read back."""
    if not line.endswith("\n"):
        line += "\n"
    data = line.encode(encoding)
    fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o666)
    try:
        if _armed("mid-append"):
            os.write(fd, data[: len(data) // 2])
            os.kill(os.getpid(), signal.SIGKILL)
        os.write(fd, data)
        os.fsync(fd)
        _kill_point("after-append")
    finally:
        os.close(fd)


def complete_lines(path: str | os.PathLike[str], encoding: str = "utf-8") -> list[str]:
    """The complete (newline-terminated) lines of an appended log, without the newline; a
    partial last line (a write that was killed) is dropped, and cut off the file so the next
    :func:`append_line` starts on a fresh line."""
    try:
        data = Path(path).read_bytes()
    except FileNotFoundError:
        return []
    end = data.rfind(b"\n") + 1
    if end < len(data):
        with open(path, "r+b") as f:
            f.truncate(end)
    return data[:end].decode(encoding, errors="replace").splitlines()


def _same_file(a: Path, b: Path) -> bool:
    try:
        return os.path.samefile(a, b)
    except OSError:
        try:
            return a.resolve() == b.resolve()
        except (OSError, RuntimeError):
            return False


def refuse_overwrite_input(out: str | os.PathLike[str] | None,
                           inputs: Iterable[str | os.PathLike[str] | None]) -> None:
    """:class:`OutputError` if ``out`` names one of ``inputs`` (same file, through links or
    relative paths too), so ``iterc compile x.lts -o x.lts`` fails before doing any work."""
    if out is None:
        return
    o = Path(out)
    for i in inputs:
        if i is not None and _same_file(o, Path(i)):
            raise OutputError(f"refusing to overwrite the input file {i} with an output "
                              "(choose another output name)")


def check_writable_dir(folder: str | os.PathLike[str]) -> None:
    """:class:`OutputError` unless ``folder`` exists (or can be created) and is writable --
    checked *before* a long run, so its outputs are not lost at the end."""
    p = Path(folder)
    try:
        p.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise OutputError(f"cannot create the output folder {p}: {e.strerror or e}") from None
    if not p.is_dir():
        raise OutputError(f"the output path {p} is not a folder")
    try:
        fd, tmp = tempfile.mkstemp(prefix=".iterplan-probe.", dir=p)
        os.close(fd)
        os.unlink(tmp)
    except OSError as e:
        raise OutputError(f"cannot write in the output folder {p}: {e.strerror or e}") from None


PARTIAL_MARKER = "RUN-INCOMPLETE.txt"


class OutputFolder:
    """The outputs of one run, published together: files are written into a staging folder
    beside the target (``.NAME.staging-PID``) and the whole folder replaces ``NAME`` only when
    the run ends normally.  A run that fails (an exception in the ``with`` block) or is killed
    never touches the previous run's ``NAME``: its files end in ``NAME.partial/`` with a
    ``RUN-INCOMPLETE.txt`` marker saying why (a killed run leaves the staging folder, marker
    included).  The target's parent folder is checked writable on entry -- before the run,
    not after it::

        with OutputFolder(args.out) as out:
            out.write_text("events.log", log)
            out.write_bytes("track.png", png)
    """

    def __init__(self, folder: str | os.PathLike[str]) -> None:
        self.final = Path(folder)
        parent = self.final.parent if str(self.final.parent) else Path(".")
        self.parent = parent
        self.stage = parent / f".{self.final.name}.staging-{os.getpid()}"

    def __enter__(self) -> OutputFolder:
        check_writable_dir(self.parent)
        if self.final.exists() and not self.final.is_dir():
            raise OutputError(f"the output path {self.final} exists and is not a folder")
        import shutil

        shutil.rmtree(self.stage, ignore_errors=True)
        self.stage.mkdir()
        atomic_write_text(self.stage / PARTIAL_MARKER,
                          "this run did not finish (killed or still running); its outputs "
                          "are incomplete\n")
        return self

    def path(self, name: str) -> Path:
        """Where to write output ``name`` during the run (inside the staging folder)."""
        return self.stage / name

    def write_text(self, name: str, text: str) -> Path:
        atomic_write_text(self.stage / name, text)
        return self.final / name

    def write_bytes(self, name: str, data: bytes) -> Path:
        atomic_write_bytes(self.stage / name, data)
        return self.final / name

    def __exit__(self, exc_type, exc, tb) -> None:
        import shutil

        if exc_type is None:
            os.unlink(self.stage / PARTIAL_MARKER)
            old = self.parent / f".{self.final.name}.previous-{os.getpid()}"
            if self.final.exists():
                os.replace(self.final, old)  # a kill right here: NAME is in .NAME.previous-*
                _kill_point("between-folders")
            os.replace(self.stage, self.final)
            _fsync_dir(self.parent)
            shutil.rmtree(old, ignore_errors=True)
            return
        partial = self.parent / f"{self.final.name}.partial"
        with contextlib.suppress(OSError):
            atomic_write_text(self.stage / PARTIAL_MARKER,
                              f"this run failed: {exc_type.__name__}: {exc}\n")
            shutil.rmtree(partial, ignore_errors=True)
            os.replace(self.stage, partial)


def user_cache_dir(name: str) -> Path | None:
    """``$XDG_CACHE_HOME/iterplan/NAME`` (default ``~/.cache``), created; None when caching is
    off (``ITERPLAN_NO_CACHE=1``) or the folder cannot be written.  A per-user folder, not the
    shared temp dir: what is cached there is trusted when read back."""
    if os.environ.get("ITERPLAN_NO_CACHE"):
        return None
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    folder = Path(base) / "iterplan" / name
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError:
        return None
    return folder if os.access(folder, os.W_OK) else None
