"""Reading user files safely and writing outputs atomically.

Every file a user hands to orientviz enters through :func:`check_input_file` (or the
readers built on it): it must be a regular file (not a folder, a named pipe, a device
such as ``/dev/zero`` — also not behind a symlink) of at most :func:`max_input_bytes`
bytes; anything else is one :class:`~orientviz.errors.InputError` naming the path,
before a single byte is read. The limit is 512 MB unless the command line's
``--max-size`` (or :func:`input_limit`) says otherwise.

Every file orientviz writes goes through :func:`write_atomic`: a temporary name in the
target folder, ``fsync``, then :func:`os.replace`, so an interrupted or failed write
leaves either the old file or the complete new one, never a half-written file. A target
that is one of the files the current command read (``solve a.json -o a.json``) is
refused: nothing the user gave is changed on disk.
"""

from __future__ import annotations

import contextlib
import contextvars
import os
import stat
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO

from ..errors import InputError

#: Largest input file read without ``--max-size`` (bytes).
DEFAULT_MAX_BYTES: int = 512 * 2**20

_limit: contextvars.ContextVar[int] = contextvars.ContextVar("max_input", default=DEFAULT_MAX_BYTES)
_explicit: contextvars.ContextVar[bool] = contextvars.ContextVar("max_input_given", default=False)
_inputs: contextvars.ContextVar[frozenset[tuple[int, int]]] = contextvars.ContextVar(
    "inputs", default=frozenset()
)


def max_input_bytes() -> int:
    """The current size limit of input files in bytes."""
    return _limit.get()


@contextlib.contextmanager
def input_limit(max_bytes: int | None) -> Iterator[None]:
    """Within the ``with`` block input files may have up to ``max_bytes`` bytes.

    Also starts a fresh record of the files read (see :func:`write_atomic`).
    """
    t1 = _limit.set(DEFAULT_MAX_BYTES if max_bytes is None else int(max_bytes))
    t2 = _inputs.set(frozenset())
    t3 = _explicit.set(max_bytes is not None)
    try:
        yield
    finally:
        _limit.reset(t1)
        _inputs.reset(t2)
        _explicit.reset(t3)


def parse_size(text: str) -> int:
    """``"200M"``, ``"1.5G"``, ``"4096"`` (bytes) → bytes; raises ValueError otherwise."""
    t = text.strip().upper().removesuffix("B")
    scale = {"K": 2**10, "M": 2**20, "G": 2**30}.get(t[-1:], 1)
    number = float(t[:-1] if scale != 1 else t)
    if not (number > 0 and number * scale < 2**62):
        raise ValueError(text)
    return int(number * scale)


def _megabytes(n: int) -> str:
    if n < 2**20:
        return f"{n} bytes" if n < 2**10 else f"{n / 2**10:.3g} KB"
    return f"{n / 2**20:.3g} MB" if n < 2**30 else f"{n / 2**30:.3g} GB"


def _kind(mode: int) -> str:
    if stat.S_ISDIR(mode):
        return "a directory"
    if stat.S_ISFIFO(mode):
        return "a named pipe"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return "not a regular file"


def check_input_file(
    path: str | os.PathLike[str], what: str = "an input file", *, capped: bool = True
) -> Path:
    """Check that ``path`` is a readable regular file within the size limit.

    Parameters
    ----------
    path : path-like
        The file as the user named it (symlinks are followed and judged by their target).
    what : str
        What was expected, for the message (``"a BAL text file"``).
    capped : bool
        True: the limit is ``--max-size`` or the default 512 MB. False (streaming readers
        whose memory does not grow with the file): only a ``--max-size`` the user gave.

    Returns
    -------
    Path

    Raises
    ------
    InputError
        ``"<path>: is a named pipe, expected a BAL text file"``, ``"no such file"``,
        ``"is 3.2 GB, larger than the limit of 512 MB (raise it with --max-size)"``.
    """
    p = Path(path)
    source = str(path)
    try:
        st = p.stat()
    except FileNotFoundError:
        raise InputError("no such file", source) from None
    except (OSError, ValueError) as exc:  # ValueError: embedded NUL in the name
        raise InputError(f"cannot open: {getattr(exc, 'strerror', None) or exc}", source) from None
    if not stat.S_ISREG(st.st_mode):
        raise InputError(f"is {_kind(st.st_mode)}, expected {what}", source)
    limit = max_input_bytes()
    if (capped or _explicit.get()) and st.st_size > limit:
        raise InputError(
            f"is {_megabytes(st.st_size)}, larger than the limit of {_megabytes(limit)} "
            "(raise it with --max-size)",
            source,
        )
    _inputs.set(_inputs.get() | {(st.st_dev, st.st_ino)})
    return p


def read_input_bytes(path: str | os.PathLike[str], what: str = "an input file") -> bytes:
    """The bytes of a checked input file (:func:`check_input_file`), read with a bound."""
    p = check_input_file(path, what)
    limit = max_input_bytes()
    try:
        with open(p, "rb") as fh:
            data = fh.read(limit + 1)
    except OSError as exc:
        raise InputError(f"cannot read: {exc.strerror or exc}", str(path)) from None
    if len(data) > limit:  # a file that grew while we read it
        raise InputError(
            f"is larger than the limit of {_megabytes(limit)} (raise it with --max-size)",
            str(path),
        )
    return data


def decode_text(data: bytes, source: str, what: str, encoding: str = "utf-8") -> str:
    """Decode ``data``; a decoding error names the byte and what was expected."""
    try:
        return data.decode(encoding)
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        raise InputError(
            f"not {encoding.upper().removesuffix('-SIG')} text (byte {exc.start}), expected {what}",
            source,
            f"line {line}",
        ) from None


def read_input_text(
    path: str | os.PathLike[str], what: str = "a text file", encoding: str = "utf-8"
) -> str:
    """The text of a checked input file; bad bytes are one :class:`InputError` with the line."""
    return decode_text(read_input_bytes(path, what), str(path), what, encoding)


def open_input_text(
    path: str | os.PathLike[str],
    what: str = "a text file",
    encoding: str = "utf-8",
    *,
    capped: bool = True,
) -> IO[str]:
    """An open text stream (``newline=""``, for :mod:`csv`) of a checked input file.

    For streaming readers: iterate it and turn a ``UnicodeDecodeError`` into an
    :class:`InputError` with the line (see :func:`orientviz.io.control.csv_rows`).
    ``capped=False``: only a ``--max-size`` the user gave limits the size.
    """
    p = check_input_file(path, what, capped=capped)
    try:
        return open(p, encoding=encoding, newline="")
    except OSError as exc:
        raise InputError(f"cannot read: {exc.strerror or exc}", str(path)) from None


# --------------------------------------------------------------------------- writing
def _is_input(target: Path) -> bool:
    try:
        st = target.stat()
    except OSError:
        return False
    return (st.st_dev, st.st_ino) in _inputs.get()


def check_output_file(path: str | os.PathLike[str]) -> Path:
    """Check that ``path`` can be written as a file: not a folder, not an input, folder exists."""
    target = Path(path)
    source = str(path)
    if target.is_dir():
        raise InputError("is a directory, expected a file name to write", source)
    if _is_input(target):
        raise InputError("is an input of this command; refusing to overwrite it", source)
    if target.exists() and not target.is_file():
        raise InputError("exists and is not a regular file; refusing to replace it", source)
    folder = target.parent if str(target.parent) else Path(".")
    if not folder.is_dir():
        raise InputError(f"cannot write: folder {str(folder)!r} does not exist", source)
    return target


def write_atomic(path: str | os.PathLike[str], data: str | bytes) -> Path:
    """Write ``data`` (text as UTF-8) to ``path`` through a temporary file and a rename.

    Either the complete new file exists afterwards or the old state is untouched; no
    half-written file is ever left behind (also not on an exception or an encoding
    error). A folder target, a missing folder, a special file or an input of the
    current command is an :class:`InputError` naming the path.

    Returns
    -------
    Path
        ``path``.
    """
    target = check_output_file(path)
    if isinstance(data, str):
        try:
            data = data.encode("utf-8")
        except UnicodeEncodeError as exc:
            raise InputError(
                f"text with a character that cannot be written ({exc.reason})", str(path)
            ) from None
    folder = target.parent if str(target.parent) else Path(".")
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{target.name[:80]}.", suffix=".tmp", dir=folder)
    except OSError as exc:
        raise InputError(f"cannot write: {exc.strerror or exc}", str(path)) from None
    try:
        try:  # keep the mode of a file we replace, else the usual 0o666 & ~umask
            mode = target.stat().st_mode & 0o777
        except OSError:
            umask = os.umask(0)
            os.umask(umask)
            mode = 0o666 & ~umask
        os.chmod(tmp, mode)
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, target)
    except BaseException as exc:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        if isinstance(exc, OSError):
            raise InputError(f"cannot write: {exc.strerror or exc}", str(path)) from None
        raise
    return target


def prepare_output_dir(path: str | os.PathLike[str]) -> Path:
    """Create the output folder ``path`` (and its parents) or refuse with one line.

    An existing file (or special file) of that name is an :class:`InputError`.
    """
    d = Path(path)
    if d.exists() and not d.is_dir():
        raise InputError("exists and is not a directory, expected a folder to write into", str(d))
    try:
        d.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"cannot create the folder: {exc.strerror or exc}", str(d)) from None
    return d
