"""Output files: checked before any work starts, written under a unique temporary name, then renamed.

Every file the package writes (datasets, sweep chunks, Moreau checkpoints, figures, animations)
goes through :func:`atomic_write`: the content is written to ``.{name}.{pid}.{random}.part`` in
the target directory, flushed to disk, and moved into place with :func:`os.replace`. A reader never
sees a half-written file, an interrupted write leaves nothing behind, and two processes writing
the same output both finish: the last rename wins.

:func:`check_output` refuses, before a computation starts, what could only fail at its end:
a path that is a directory or a device, a missing or unwritable directory, a file name netCDF
cannot encode, or (unless ``overwrite``) an existing file.
"""

from __future__ import annotations

import contextlib
import errno
import os
import re
import secrets
import signal
import stat
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

from .errors import OutputError

PART_SUFFIX = ".part"


def show(path: str | os.PathLike) -> str:
    """``path`` printable in any terminal: bytes that are not UTF-8 shown as ``\\xNN``."""
    return os.fsencode(os.fspath(path)).decode("utf-8", "backslashreplace")


def utf8_encodable(path: str | os.PathLike) -> bool:
    """True if ``path`` is valid UTF-8 (netCDF-C and HDF5 cannot open other names)."""
    try:
        os.fsencode(os.fspath(path)).decode("utf-8")
    except UnicodeDecodeError:
        return False
    return True


def temporary_name(path: str | os.PathLike, keep_suffix: bool = False) -> Path:
    """A name unique to this process and call, next to ``path``: ``.{name}.{pid}.{random}.part``
    (``keep_suffix``: ``...part.gif``, for writers that choose the format by the suffix)."""
    path = Path(path)
    return path.with_name(f".{path.name}.{os.getpid()}.{secrets.token_hex(4)}{PART_SUFFIX}"
                          + (path.suffix if keep_suffix else ""))


@contextlib.contextmanager
def deferred_interrupt() -> Iterator[None]:
    """Hold Ctrl-C (SIGINT) until the block is done, then raise KeyboardInterrupt.

    netCDF-C / HDF5 and xarray's file locks do not survive an exception raised in the middle of a
    write or read: the process would hang or leave a locked file. Writes take milliseconds, so
    Ctrl-C waits for them. Only the main thread receives signals; elsewhere this does nothing.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    received = []
    try:
        previous = signal.signal(signal.SIGINT, lambda signum, frame: received.append(signum))
    except ValueError:  # pragma: no cover - signals unavailable (e.g. embedded interpreters)
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous if previous is not None else signal.default_int_handler)
        if received:
            raise KeyboardInterrupt


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # pragma: no cover - another user's process
        return True
    return True


def remove_stale_parts(path: str | os.PathLike) -> None:
    """Remove temporary files of ``path`` left by processes that died (``kill -9``, power loss)."""
    path = Path(path)
    pattern = re.compile(re.escape(f".{path.name}.") + r"(\d+)\.[0-9a-f]+" + re.escape(PART_SUFFIX))
    try:
        candidates = list(path.parent.glob(f".{glob_escape(path.name)}.*{PART_SUFFIX}*"))
    except OSError:
        return
    for candidate in candidates:
        match = pattern.match(candidate.name)
        if match and int(match.group(1)) != os.getpid() and not _pid_alive(int(match.group(1))):
            with contextlib.suppress(OSError):
                candidate.unlink()


HOLD_VARIABLE = "TIPPEDISK_HOLD_AFTER"


def hold_for_interrupt(event: str) -> None:
    """A hook for interrupt tests: when the environment variable TIPPEDISK_HOLD_AFTER names ``event``
    ("checkpoint", "chunk"), the process waits here, just after that event, until Ctrl-C (SIGINT) ends it, so a
    test triggers on the event and never races a run that finishes within milliseconds of it."""
    if os.environ.get(HOLD_VARIABLE) == event:
        while True:
            time.sleep(0.01)


def glob_escape(name: str) -> str:
    return re.sub(r"([*?\[])", r"[\1]", name)


def check_output(path: str | os.PathLike, *, overwrite: bool = True, netcdf: bool = True,
                 option: str = "--output") -> Path:
    """``path`` as a :class:`Path` if a file can be written there; else :class:`OutputError`.

    Refused: a directory, a device / pipe / socket, a missing directory, a directory this process
    cannot create files in (tested by creating one, so it holds for root and read-only mounts),
    a name that is not UTF-8 (``netcdf``), and an existing file unless ``overwrite``.
    ``option`` names the command-line option in the CLI wording of the message.
    """
    path = Path(path)
    shown = show(path)
    if netcdf and not utf8_encodable(path):
        raise OutputError(f"'{shown}' is not valid UTF-8, which netCDF cannot write; choose a UTF-8 file name",
                          cli=f"'{shown}' is not valid UTF-8, which netCDF cannot write; give {option} a UTF-8 name")
    if path.is_dir():
        raise OutputError(f"'{shown}' is a directory; give a file name, e.g. '{show(path / 'result.nc')}'",
                          cli=f"'{shown}' is a directory; give {option} a file name, e.g. "
                              f"'{show(path / 'result.nc')}'")
    if path.exists() or path.is_symlink():
        mode = os.stat(path).st_mode if path.exists() else 0
        if not stat.S_ISREG(mode):
            raise OutputError(f"'{shown}' is not a regular file (a device, pipe, socket or broken link); "
                              "choose a file name", cli=f"'{shown}' is not a regular file (a device, pipe, socket "
                                                         f"or broken link); give {option} a file name")
        if not overwrite:
            raise OutputError(f"'{shown}' exists; pass overwrite=True to replace it, or choose another name",
                              cli=f"'{shown}' exists; give --overwrite to replace it, or another {option}")
    parent = path.parent
    if not parent.is_dir():
        raise OutputError(f"directory '{show(parent)}' does not exist; create it or choose another path",
                          cli=f"directory '{show(parent)}' does not exist; create it or give another {option}")
    probe = temporary_name(path.with_name("probe"))
    try:
        fd = os.open(probe, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    except OSError as exc:
        reason = exc.strerror or exc.__class__.__name__
        raise OutputError(f"cannot create files in '{show(parent)}' ({reason}); choose another directory",
                          cli=f"cannot create files in '{show(parent)}' ({reason}); give another {option}") from None
    os.close(fd)
    os.unlink(probe)
    remove_stale_parts(path)
    return path


def atomic_write(path: str | os.PathLike, write: Callable[[Path], None], keep_suffix: bool = False,
                 interruptible: bool = False) -> Path:
    """Call ``write(tmp)`` to fill a temporary file next to ``path``, flush it, rename it to ``path``.

    Ctrl-C during the write is held until the file is in place (:func:`deferred_interrupt`), unless
    ``interruptible`` (long writers that Ctrl-C can stop safely, e.g. animations): then only the
    rename is held. ``keep_suffix``: the temporary name ends with the suffix of ``path`` (writers
    that choose the format by it). The temporary file is removed
    whatever happens (errors, Ctrl-C). A failing write raises
    :class:`OutputError` naming the path and the operating system's reason.
    """
    path = Path(path)
    if path.exists() and not path.is_file():  # never replace a device or a directory entry of another kind
        raise OutputError(f"'{show(path)}' is not a regular file (a directory, device, pipe or socket); "
                          "choose a file name")
    tmp = temporary_name(path, keep_suffix)
    try:
        with contextlib.nullcontext() if interruptible else deferred_interrupt():
            write(tmp)  # netCDF: Ctrl-C waits for the write (an HDF5 write interrupted midway can hang)
        with deferred_interrupt():
            fd = os.open(tmp, os.O_RDONLY)
            try:
                os.fsync(fd)
            finally:
                os.close(fd)
            os.replace(tmp, path)
    except OSError as exc:
        reason = exc.strerror or str(exc) or exc.__class__.__name__
        if exc.errno == errno.ENOSPC:
            raise OutputError(f"cannot write '{show(path)}': the disk is full ({reason}); free space or choose "
                              "another path") from None
        raise OutputError(f"cannot write '{show(path)}' ({reason}); check the disk space and the directory's "
                          "permissions, or choose another path") from None
    except RuntimeError as exc:  # netCDF-C reports a failed write (e.g. a full disk) as "NetCDF: HDF error"
        if not str(exc).startswith("NetCDF"):
            raise
        raise OutputError(f"cannot write '{show(path)}' ({exc}: the disk may be full); free space or choose "
                          "another path") from None
    finally:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        except OSError:  # pragma: no cover - e.g. the directory vanished
            pass
    return path
