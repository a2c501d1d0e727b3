"""Which paths a command may read and write, and the one writer of every output.

Inputs are regular files within a size; outputs never name an input, a device, a FIFO, a symbolic link or
each other, and no file output lies inside a folder output. All are checked before any work. `write` makes
each file beside its name (flushed to disk) and renames it over the name only when the whole command has
succeeded (`staged`), so a command that fails writes nothing and leaves every old file as it was, no
command writes over what it reads (the same device and inode: hard links and symlinks alike), and none
writes through or replaces a link, even one planted in an output folder during the run."""
import contextlib
import os
import stat
import tempfile
from pathlib import Path

from ..errors import DataError

#: (device, inode) of every input of the running command: the writers refuse to replace them.
_INPUTS = set()
#: The outputs of the running command (None outside `staged`): path -> its complete temporary file.
_STAGED = None
#: Output folders made by the running command (removed again, when empty, if it fails).
_MADE = []
#: Output folders checked or made -> their (device, inode): a folder swapped during the run is refused.
_FOLDERS = {}


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


def regular(path, what="the file", max_bytes=None, param="path"):
    """`path` if it can be read as an input (see `problem`); else DataError naming the file (and `param`, the
    argument it was given as)."""
    why = problem(path, what, max_bytes)
    if why:
        raise DataError(f"{path}: {why}", param=param)
    return path


#: The longest header line a text input may have (characters).
MAX_HEADER = 65_536


def header_line(fh, path, param="path"):
    """The first line of an open text file (at most MAX_HEADER characters, else DataError): every reader
    takes the header from here, so none reads past a long one differently from another."""
    line = fh.readline(MAX_HEADER + 1)
    if len(line) > MAX_HEADER:
        raise DataError(f"{path}: the header line is longer than {MAX_HEADER:,} characters", param=param)
    return line


def json_text(text, parse_int=None):
    """Strict JSON of a user's file: a key given twice in one object, NaN and Infinity refused (ValueError
    naming it), never silently one of two values or a number no comparison can bound."""
    import json

    def unique(pairs):
        seen = set()
        for k, _ in pairs:
            if k in seen:
                raise ValueError(f"the key {k[:60]!r} appears twice in one object")
            seen.add(k)
        return dict(pairs)

    def constant(name):
        raise ValueError(f"{name} is not a number JSON allows")
    return json.loads(text, parse_int=parse_int, parse_constant=constant, object_pairs_hook=unique)


def read_json(path, what, max_bytes=1_000_000, param="path"):
    """A user's small JSON file (a section list, a truth, an imucal calibration), strict as `json_text`;
    DataError naming the file and `what` it should be."""
    regular(path, what, max_bytes, param)
    try:
        with open(path, "rb") as fh:
            return json_text(fh.read(max_bytes + 1).decode("utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError) as e:
        raise DataError(f"{path}: not {what} ({str(e).splitlines()[0][:120]})", param=param) from None


def _identity(path):
    try:
        st = os.stat(path)
    except OSError:
        return None
    return st.st_dev, st.st_ino


def check_inputs(paths, param="inputs"):
    """Every existing path among a command's inputs must be a regular file or a folder (a FIFO or a device
    would hang or never end); each is remembered so that no output replaces it. An entry may be (path, the
    argument that names it)."""
    _INPUTS.clear()
    for p in paths:
        p, name = p if isinstance(p, tuple) else (p, param)
        try:
            st = os.stat(p)
        except OSError:
            continue                               # not a path (a model name) or missing: the reader says so
        if not (stat.S_ISREG(st.st_mode) or stat.S_ISDIR(st.st_mode)):
            raise DataError(f"{p}: an input must be a regular file, not {_kind(st.st_mode)}", param=name)
        if stat.S_ISREG(st.st_mode):
            _INPUTS.add((st.st_dev, st.st_ino))


def check_outputs(outputs):
    """Each (path, what, 'file' or 'folder'[, param]) before any work (param: the argument that names it): a file's
    folder exists and is writable, the name has no trailing slash, it is not an input, a link, a device, a FIFO or a
    folder, no two outputs name the same file and none lies inside an output folder (where the folder's own files
    could take its name); a folder can be made."""
    seen = {}
    outputs = [(*o, "path") if len(o) == 3 else tuple(o) for o in outputs]
    folders = [(os.path.realpath(path), path, what, param) for path, what, kind, param in outputs if kind == "folder"]
    for i, (real, path, what, param) in enumerate(folders):
        _check_folder(path, what, param)
        for real2, path2, what2, _ in folders[:i]:
            if _within(real, real2) or _within(real2, real):
                raise DataError(f"{path}: {what} and {what2} ({path2}) overlap; give each its own folder", param=param)
    for path, what, kind, param in outputs:
        if kind == "folder":
            continue
        text = str(path)
        if text.endswith(("/", os.sep)):
            raise DataError(f"{text}: {what} is a file name; remove the trailing slash", param=param)
        p = Path(path)
        parent = p.parent if str(p.parent) else Path(".")
        for real, folder, folder_what, _ in folders:
            if _within(os.path.realpath(p), real):
                raise DataError(f"{p}: {what} lies inside {folder_what} ({folder}), whose files could take its "
                                "name; write it elsewhere", param=param)
        _refuse_link(p, what, param)
        if os.path.lexists(p):
            st = os.stat(p) if p.exists() else None
            if st is not None and not stat.S_ISREG(st.st_mode):
                raise DataError(f"{p}: {what} would be written over {_kind(st.st_mode)}; choose a file name",
                                param=param)
            if st is not None and (st.st_dev, st.st_ino) in _INPUTS:
                raise DataError(f"{p}: {what} would be written over an input of this command; choose another name",
                                param=param)
        if not parent.is_dir():
            raise DataError(f"{p}: the folder {parent} for {what} does not exist", param=param)
        if not _can_create(parent):               # tried, not guessed: /proc/self/fd says writable and is not
            raise DataError(f"{p}: the folder {parent} for {what} is not writable", param=param)
        key = os.path.realpath(p)
        if key in seen:
            raise DataError(f"{p}: {what} and {seen[key]} name the same file; give each its own", param=param)
        seen[key] = what


def _within(path, folder):
    """True when the real path `path` is `folder` or lies under it."""
    return path == folder or path.startswith(folder.rstrip(os.sep) + os.sep)


def _refuse_link(path, what="the output", param="path"):
    if os.path.islink(path):
        raise DataError(f"{path}: {what} is a symbolic link; garant neither writes through a link nor replaces one: "
                        "remove it or choose another name", param=param)


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


def _check_folder(path, what, param="path"):
    if os.path.exists(path) and not os.path.isdir(path):
        raise DataError(f"{path}: {what} exists and is not a folder", param=param)
    up = os.path.dirname(os.path.abspath(path))
    while not os.path.exists(up):                  # the first ancestor that exists must be a writable folder
        up = os.path.dirname(up)
    if not os.path.isdir(up) or not os.access(up, os.W_OK):
        raise DataError(f"{path}: {what} cannot be made: {up} is not a writable folder", param=param)
    if os.path.isdir(path):
        for entry in os.scandir(path):             # what the folder's writers could replace, file by file
            if not entry.name.endswith(FOLDER_OUTPUTS):
                continue
            if entry.is_symlink():
                raise DataError(f"{entry.path}: a symbolic link in {what}; garant neither writes through a link "
                                "nor replaces one: remove it or choose another folder", param=param)
            if _identity(entry.path) in _INPUTS:
                raise DataError(f"{entry.path}: an input of this command lies in {what}, where an output could "
                                "take its name; choose another folder", param=param)


#: The endings of the files an output folder receives (reports, plots, generated modules, certificates).
FOLDER_OUTPUTS = (".md", ".html", ".png", ".py", ".json")


def refuse_input(path, param="path"):
    """DataError if `path` is an input of the running command (called by every writer just before it
    replaces a file: a folder output may hold an input of the same name)."""
    if _identity(path) in _INPUTS:
        raise DataError(f"{path}: would be written over an input of this command; nothing written there", param=param)


def make_folder(path, param="out"):
    """An output folder, made with its parents if missing (and removed again if the command fails); a
    folder given as a symbolic link is followed once, here, and the folder it names is the one written to."""
    path = Path(path)
    if os.path.islink(path) and not os.path.exists(path):
        raise DataError(f"{path}: an output folder given as a link to nowhere (or a loop of links); give a folder",
                        param=param)
    missing = [p for p in [path, *path.parents] if not os.path.lexists(p)]
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise DataError(f"{path}: the output folder cannot be made ({e.strerror})", param=param) from None
    if _STAGED is not None:
        _MADE.extend(missing)                       # deepest first: removed in this order
    st = os.stat(path)
    if not stat.S_ISDIR(st.st_mode):
        raise DataError(f"{path}: an output folder must be a folder, not {_kind(st.st_mode)}", param=param)
    if not os.access(path, os.W_OK | os.X_OK):
        raise DataError(f"{path}: the output folder is not writable", param=param)
    if os.path.islink(path):                        # followed once: the folder it names is the one written to
        path = Path(os.path.realpath(path))
    _FOLDERS[os.path.abspath(path)] = (st.st_dev, st.st_ino)
    return path


def _check_place(path, param="path"):
    """Before a file is made or renamed into place: not a link, not an input, and its folder the one
    checked when the command began (a folder swapped for a link during the run is refused)."""
    _refuse_link(path)
    refuse_input(path)
    if os.path.lexists(path) and not os.path.isfile(path):
        raise DataError(f"{path}: a folder or another non-file is in the way of this output; nothing written",
                        param=param)
    folder = os.path.abspath(path.parent if str(path.parent) else ".")
    if folder in _FOLDERS and _identity_nofollow(folder) != _FOLDERS[folder]:
        raise DataError(f"{path.parent}: the output folder changed during the run (replaced or made a link); "
                        "nothing written there", param=param)


def _identity_nofollow(path):
    try:
        st = os.lstat(path)
    except OSError:
        return None
    return (st.st_dev, st.st_ino) if stat.S_ISDIR(st.st_mode) else None


def _umask():
    """The process's umask (read by setting it, then restoring it)."""
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write(path, chunks, mode="wb", param="path"):
    """Write the pieces `chunks` yields (text or bytes, as `mode` says) as the file `path`: made beside it,
    flushed to disk, then renamed over it (at once, or when the command succeeds inside `staged`). The file
    gets the permissions open() would give it (0666 less the umask), not the temporary file's 0600. A
    write that fails (a full disk, `ulimit -f`) leaves the old file as it was."""
    path = Path(path)
    _check_place(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent if str(path.parent) else ".", prefix=f".{path.name}.",
                               suffix=".part")
    try:
        os.fchmod(fd, 0o666 & ~_umask())
        with os.fdopen(fd, mode) as fh:
            for chunk in chunks:
                fh.write(chunk)
            fh.flush()
            os.fsync(fh.fileno())
    except OSError as e:
        os.unlink(tmp)
        raise DataError(f"{path}: cannot be written ({e.strerror}); the old file, if any, is unchanged",
                        param=param) from None
    except BaseException:
        os.unlink(tmp)
        raise
    if _STAGED is None:
        _place(tmp, path)
        return
    old = _STAGED.pop(path, None)
    if old is not None:
        os.unlink(old)
    _STAGED[path] = tmp


def written(path):
    """The bytes of an output written by this command (still staged, or in place)."""
    path = Path(path)
    source = _STAGED.get(path, path) if _STAGED is not None else path
    with open(source, "rb") as fh:
        return fh.read()


def _place(tmp, path):
    try:
        _check_place(path)
        os.replace(tmp, path)
    except BaseException:
        os.unlink(tmp)
        raise


@contextlib.contextmanager
def staged():
    """The outputs of one command: each `write` is held complete beside its name and renamed into place
    only when the block ends without an exception; otherwise every one is removed (and the folders the
    command made, when empty), so a command that fails writes nothing."""
    global _STAGED
    _STAGED, _MADE[:], before = {}, [], dict(_FOLDERS)
    try:
        yield
        pending = list(_STAGED.items())
        _STAGED = None
        for i, (path, tmp) in enumerate(pending):
            try:
                _place(tmp, path)
            except BaseException:
                for _, rest in pending[i + 1:]:
                    os.unlink(rest)
                raise
    except BaseException:
        for tmp in (_STAGED or {}).values():
            os.unlink(tmp)
        for folder in _MADE:
            with contextlib.suppress(OSError):
                os.rmdir(folder)
        raise
    finally:
        _STAGED = None
        _MADE.clear()
        _FOLDERS.clear()
        _FOLDERS.update(before)
