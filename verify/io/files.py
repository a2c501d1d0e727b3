"""Which paths a command may read and write: inputs are regular files within a size, outputs never name
an input, a device, a FIFO or each other. Checked before any work, so a command that fails writes nothing
and no command ever writes over what it reads (symlinks resolved: the same device and inode)."""
import os
import stat
from pathlib import Path

from ..errors import DataError

#: (device, inode) of every input of the running command: the writers refuse to replace them.
_INPUTS = set()


def _kind(mode):
    for test, name in ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO"), (stat.S_ISCHR, "a character device"),
                       (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return name
    return "not a regular file"


def problem(path, what="the file", max_bytes=None):
    """Why `path` cannot be read as an input (not a regular file, symlinks followed, or over `max_bytes`),
    or None. Never opens the file (a FIFO would block)."""
    try:
        st = os.stat(path)
    except OSError as e:
        return f"cannot read {what} ({e.strerror})"
    if not stat.S_ISREG(st.st_mode):
        return f"{what} must be a regular file, not {_kind(st.st_mode)}"
    if max_bytes is not None and st.st_size > max_bytes:
        return f"{what} is {st.st_size / 1e6:.4g} MB, over the limit of {max_bytes / 1e6:g} MB"
    return None


def regular(path, what="the file", max_bytes=None):
    """`path` if it can be read as an input (see `problem`); else DataError naming the file."""
    why = problem(path, what, max_bytes)
    if why:
        raise DataError(f"{path}: {why}")
    return path


#: The longest header line a text input may have (characters).
MAX_HEADER = 65_536


def header_line(fh, path):
    """The first line of an open text file (at most MAX_HEADER characters, else DataError): every reader
    takes the header from here, so none reads past a long one differently from another."""
    line = fh.readline(MAX_HEADER + 1)
    if len(line) > MAX_HEADER:
        raise DataError(f"{path}: the header line is longer than {MAX_HEADER:,} characters")
    return line


def _identity(path):
    try:
        st = os.stat(path)
    except OSError:
        return None
    return st.st_dev, st.st_ino


def check_inputs(paths):
    """Every existing path among a command's inputs must be a regular file or a folder (a FIFO or a device
    would hang or never end); each is remembered so that no output replaces it."""
    _INPUTS.clear()
    for p in paths:
        try:
            st = os.stat(p)
        except OSError:
            continue                               # not a path (a model name) or missing: the reader says so
        if not (stat.S_ISREG(st.st_mode) or stat.S_ISDIR(st.st_mode)):
            raise DataError(f"{p}: an input must be a regular file, not {_kind(st.st_mode)}")
        if stat.S_ISREG(st.st_mode):
            _INPUTS.add((st.st_dev, st.st_ino))


def check_outputs(outputs):
    """Each (path, what, 'file' or 'folder') before any work: a file's folder exists and is writable, the
    name has no trailing slash, it is not an input, a device, a FIFO or a folder, and no two outputs
    name the same file; a folder can be made."""
    seen = {}
    for path, what, kind in outputs:
        if kind == "folder":
            _check_folder(path, what)
            continue
        text = str(path)
        if text.endswith(("/", os.sep)):
            raise DataError(f"{text}: {what} is a file name; remove the trailing slash")
        p = Path(path)
        parent = p.parent if str(p.parent) else Path(".")
        if os.path.lexists(p):
            st = os.stat(p) if p.exists() else None
            if st is not None and not stat.S_ISREG(st.st_mode):
                raise DataError(f"{p}: {what} would be written over {_kind(st.st_mode)}; choose a file name")
            if st is not None and (st.st_dev, st.st_ino) in _INPUTS:
                raise DataError(f"{p}: {what} would be written over an input of this command; choose another name")
        if not parent.is_dir():
            raise DataError(f"{p}: the folder {parent} for {what} does not exist")
        if not _can_create(parent):               # tried, not guessed: /proc/self/fd says writable and is not
            raise DataError(f"{p}: the folder {parent} for {what} is not writable")
        key = os.path.realpath(p)
        if key in seen:
            raise DataError(f"{p}: {what} and {seen[key]} name the same file; give each its own")
        seen[key] = what


def _can_create(folder):
    """True when a file can be made in `folder` (the writers make their temporary file there)."""
    import tempfile
    try:
        fd, tmp = tempfile.mkstemp(dir=folder, prefix=".garant-check.", suffix=".part")
    except OSError:
        return False
    os.close(fd)
    os.unlink(tmp)
    return True


def _check_folder(path, what):
    if os.path.exists(path) and not os.path.isdir(path):
        raise DataError(f"{path}: {what} exists and is not a folder")
    up = os.path.dirname(os.path.abspath(path))
    while not os.path.exists(up):                  # the first ancestor that exists must be a writable folder
        up = os.path.dirname(up)
    if not os.path.isdir(up) or not os.access(up, os.W_OK):
        raise DataError(f"{path}: {what} cannot be made: {up} is not a writable folder")


def refuse_input(path):
    """DataError if `path` is an input of the running command (called by every writer just before it
    replaces a file: a folder output may hold an input of the same name)."""
    if _identity(path) in _INPUTS:
        raise DataError(f"{path}: would be written over an input of this command; nothing written there")
