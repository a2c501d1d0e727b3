"""The models the command line knows: built-in generated modules, or a stand description file."""
from __future__ import annotations

import importlib
import math
import os
import types
from pathlib import Path
from typing import TYPE_CHECKING

from garant.generated import API, MODELS as REGISTRY

from .errors import DataError

if TYPE_CHECKING:                                   # numpy is loaded only by the functions that use it
    import numpy

#: The built-in models (the registry `python -m derive` renders in generated/__init__.py): name -> module.
MODELS = {name: f"garant.generated.{e['module']}" for name, e in REGISTRY.items()}
STANDS = [name for name, e in REGISTRY.items() if e["kind"] == "stand"]     # stand models (plan, estimate)


def kind(name: str) -> str:
    """What a model name is: "stand" (a built-in stand, a STAND.toml or a module `garant derive --out` wrote),
    "norm" (the norm relation of 001), or None (not a model garant knows)."""
    if str(name).endswith((".toml", ".py")):
        return "stand"
    return REGISTRY.get(name, {}).get("kind")


def load(name: str | os.PathLike) -> types.ModuleType:
    """The generated module of a built-in model, of a description file (derived, or from the cache), or
    a module `garant derive STAND.toml --out DIR` wrote (DIR/stand.py); checked once here against the
    protocol of its kind (API: the names every module of that kind exports), so no caller needs a default."""
    if str(name).endswith(".toml"):
        mod = from_description(name)
    elif str(name).endswith(".py"):
        mod = from_generated_file(name)
    elif name in MODELS:
        mod = importlib.import_module(MODELS[name])
    else:
        raise DataError(f"unknown model {name!r}; built-in models: {', '.join(MODELS)}, a STAND.toml, or the "
                        f"STAND.py `garant derive --out` writes", param="model")
    missing = [n for n in API[kind(name)] if not hasattr(mod, n)]
    if missing:
        more = ", ..." if len(missing) > 3 else ""
        raise DataError(f"{name}: not a {kind(name)} model of this garant (no {', '.join(missing[:3])}{more}); "
                        "derive it again (`garant derive STAND.toml --out DIR`)", param="model")
    return mod


def cache_dir():
    """Where derived descriptions are kept: $GARANT_CACHE, else $XDG_CACHE_HOME/garant (~/.cache/garant)."""
    if os.environ.get("GARANT_CACHE"):
        return Path(os.environ["GARANT_CACHE"])
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "garant"


def generator_version():
    """SHA-256 of garant's version and of every source file and template of derive/: a change to the
    generator makes every cached module stale."""
    import garant
    root = Path(__file__).resolve().parent.parent / "derive"
    import hashlib
    h = hashlib.sha256(garant.__version__.encode())
    for f in sorted(root.rglob("*")):
        if f.suffix in (".py", ".jinja", ".toml") and f.is_file():
            h.update(str(f.relative_to(root)).encode() + b"\0" + f.read_bytes())
    return h.hexdigest()


def _description_bytes(path):
    """The bytes of a stand description (at most 1,000,001: the reader refuses more), a regular file only."""
    try:
        if os.path.exists(path) and not os.path.isfile(path):    # a FIFO would block, a device never end
            raise DataError(f"{path}: the stand description must be a regular file", param="model")
        with open(path, "rb") as fh:
            return fh.read(1_000_001)
    except OSError as e:
        raise DataError(f"{path}: cannot read ({e.strerror})", param="model") from None


def _cached(key_bytes, make):
    """(stand name, module text): the cache entry made from `key_bytes` by this very generator (keyed by SHA-256
    of both; a stale entry is never used), else `make()`'s, kept in the cache (best effort)."""
    import hashlib
    key = hashlib.sha256(key_bytes + generator_version().encode()).hexdigest()
    folder = _cache_folder()
    hit = _entry(folder / f"{key}.py") if folder is not None else None
    if hit is not None:
        return hit
    name, text = make()
    _keep(cache_dir(), f"{key}.py", name, text)
    return name, text


def _derived(model):
    """(stand name, module text) of a derive Model (SymPy)."""
    from garant.derive import codegen
    return model.stand.name, codegen.model_files(model)[f"generated/{model.stand.name}.py"]


def _load_description(path):
    from garant.derive import description
    try:
        return description.load(path)
    except description.DescriptionError as e:
        raise DataError(str(e), param="model") from None


def from_description(path: str | os.PathLike) -> types.ModuleType:
    """The rendered module of a stand description: from the cache when one was derived from these very
    bytes by this very generator, else derived (SymPy), kept in the cache (best effort), and executed. No
    file beside the description is written."""
    name, text = _cached(_description_bytes(path), lambda: _derived(_load_description(path)))
    return _execute(text, name, Path(path).resolve())


def thermal(model: str, degree: int, t0: float) -> types.ModuleType:
    """The thermal extension of a built-in stand or a description (each block parameter a polynomial of
    `degree` in T about t0, derive/effects.py `thermal`): derived once and kept in the cache like a
    description (keyed by the base, the degree and t0)."""
    from garant.derive import builtin, effects
    toml = str(model).endswith(".toml")
    if not (toml or model in STANDS):
        raise DataError(f"a thermal calibration takes a stand: {', '.join(STANDS)} or a STAND.toml, not {model!r}",
                        param="model")
    base = _description_bytes(model) if toml else model.encode()

    def make():
        stand = _load_description(model) if toml else builtin.MODELS[model.replace("-", "_")]
        return _derived(effects.extend(stand, [effects.thermal_name(degree, t0)]))
    name, text = _cached(base + f"|thermal {degree} {t0}|".encode(), make)
    return _execute(text, name, Path(f"{model}+thermal{degree}"))


ENTRY_BYTES = 4_000_000       # a cache entry larger than this is not one garant wrote


def _cache_folder():
    """The cache folder when it exists, after the checks that keep others' code out of it: a directory (not a
    link) owned by this user and writable by no one else; None when it does not exist yet. DataError naming
    it otherwise: anyone who can write there could plant a module that garant would run."""
    folder = cache_dir()
    try:
        st = os.lstat(folder)
    except FileNotFoundError:
        return None
    except OSError as e:
        raise DataError(f"{folder}: the cache folder cannot be read ({e.strerror}); set $GARANT_CACHE",
                        param="model") from None
    import stat
    if not stat.S_ISDIR(st.st_mode):
        raise DataError(f"{folder}: the cache folder is not a directory (or is a link); set $GARANT_CACHE to one",
                        param="model")
    if st.st_uid != os.geteuid() or st.st_mode & 0o022:
        raise DataError(f"{folder}: the cache folder is owned by someone else or writable by others, so its modules "
                        "could be anyone's code; make it yours and private (chmod 700) or set $GARANT_CACHE",
                        param="model")
    return folder


def _entry(path):
    """(stand name, module text) of a cache entry garant wrote, or None (then it is derived again and replaced):
    a regular file (no link, FIFO or device) owned by this user, of bounded size, whose first line records the
    stand's name and the SHA-256 of the rest, which must match."""
    import hashlib
    import stat
    try:
        st = os.lstat(path)
        if not stat.S_ISREG(st.st_mode) or st.st_uid != os.geteuid() or st.st_size > ENTRY_BYTES:
            return None
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0))
        with os.fdopen(fd, "rb") as fh:
            data = fh.read(ENTRY_BYTES + 1)
    except OSError:
        return None
    head, _, body = data.partition(b"\n")
    parts = head.decode("ascii", "replace").split()
    if len(parts) != 4 or parts[:2] != ["#", "garant-cache"] or not parts[2].isidentifier():
        return None
    if hashlib.sha256(body).hexdigest() != parts[3]:
        return None
    try:
        return parts[2], body.decode("utf-8")
    except UnicodeDecodeError:
        return None


def _keep(folder, name, stand, text):
    """Write a cache entry atomically (a reader sees all of it or none), its first line the stand's name and
    the SHA-256 of the module, or nothing if it cannot be written: without a cache the next command derives
    again. A new cache folder is private to this user."""
    import hashlib
    body = text.encode("utf-8")
    try:
        folder.mkdir(mode=0o700, parents=True, exist_ok=True)
        if _cache_folder() is None:
            return
        import tempfile
        fd, tmp = tempfile.mkstemp(dir=folder, prefix=".", suffix=".part")
        with os.fdopen(fd, "wb") as fh:
            fh.write(f"# garant-cache {stand} {hashlib.sha256(body).hexdigest()}\n".encode("ascii") + body)
        os.replace(tmp, folder / name)
    except (OSError, DataError):
        pass


def from_generated_file(path):
    """A module `garant derive STAND.toml --out DIR` wrote: executed as the module it is (it is code the
    user names on the command line, as `python` would run it); its header must say garant generated it."""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as e:
        raise DataError(f"{path}: cannot read a generated module ({getattr(e, 'strerror', None) or e})",
                        param="model") from None
    if not text.startswith("# Generated by garant from") or "\nANGLES = " not in text:
        raise DataError(f"{path}: not a stand module written by `garant derive --out` (no garant header)",
                        param="model")
    if "\nMOUNTINGS = " not in text or "garant.generated._runtime" not in text:
        raise DataError(f"{path}: written by an older garant; derive it again (`garant derive STAND.toml --out DIR`)",
                        param="model")
    return _execute(text, Path(path).stem, Path(path).resolve())


def _execute(text, name, source):
    mod = types.ModuleType(name)
    mod.__file__ = str(source)
    exec(compile(text, f"generated/{name}.py", "exec"), mod.__dict__)
    return mod


def stand_model(name: str) -> types.ModuleType:
    """The symbolic Model (derive/) of a built-in stand or of a description file."""
    from garant.derive import description
    from garant.derive.builtin import MODELS as BUILTIN
    if str(name).endswith(".toml"):
        try:
            return description.load(name)
        except description.DescriptionError as e:
            raise DataError(str(e), param="model") from None
    key = name.replace("-", "_")
    if key not in BUILTIN:
        raise DataError(f"unknown stand {name!r}; use {', '.join(STANDS)} or a STAND.toml", param="model")
    return BUILTIN[key]


def symbolic_H(mod):
    """The symbolic H (rows: 3 per mounting) and the angle symbols of a stand module, re-derived from
    its description (built-in or the TOML file it was loaded from)."""
    from garant.derive.derivation import derive
    source = getattr(mod, "__file__", "") or ""
    name = source if source.endswith(".toml") else mod.__name__.rsplit(".", 1)[-1].replace("_", "-")
    d = derive(stand_model(name))
    return d.ident.H, d.model.angle_symbols


def load_remount(name):
    """The generated remount module (25)-(29) of a built-in model, or None."""
    load(name)
    remount = REGISTRY.get(name, {}).get("remount")
    return importlib.import_module(f"garant.generated.{remount}") if remount else None


def reachable_grid(ranges, detents, step, limit=1_000_000, what="the grid", raise_with=None):
    """Positions (degrees, (S, n)) a stand can take on a grid: each angle at its detents when it has
    them, else at the multiples of `step` (one per angle, or one for all) inside its range. A grid of
    more than `limit` positions is refused before it is built (`raise_with`: the option that raises it)."""
    import numpy as np
    steps = list(step) if np.ndim(step) else [step] * len(ranges)
    cells = [len(det) if len(det) else (min(hi - lo, 360) + 1e-9) / st for (lo, hi), det, st in zip(ranges, detents,
                                                                                                    steps)]
    size = math.prod(c if isinstance(c, int) else math.floor(c) + 1 if c < 1e18 else math.inf for c in cells)
    if size > limit:
        more = f", or raise {raise_with}" if raise_with else ""
        raise DataError(f"{what} has {size:.3g} positions".replace("inf positions",
                                                                   "more than 1e18 positions") + f", over the limit of "
                                                                       f"{limit:,}: use a coarser step{more}",
                        param="model")
    values = []
    for (lo, hi), det, st in zip(ranges, detents, steps):
        values.append(np.asarray(det, float) if len(det) else
                      np.arange(np.ceil(lo / st) * st, min(hi, lo + 360 - 1e-9) + 1e-9, st))
    return np.array(np.meshgrid(*values, indexing="ij")).reshape(len(values), -1).T


def unreachable(ranges, detents, P):
    """The first (position index, angle index, value) a stand cannot take, or None."""
    import numpy as np
    P = np.atleast_2d(np.asarray(P, float))
    for i, ((lo, hi), det) in enumerate(zip(ranges, detents)):
        v = P[:, i]
        if len(det):
            bad = ~np.isclose(((v[:, None] - np.asarray(det, float)[None]) + 180) % 360 - 180, 0, atol=1e-6).any(axis=1)
        else:
            w = lo + (v - lo) % 360
            bad = (w > hi + 1e-9) & ~np.isclose(v, hi)
        if bad.any():
            k = int(np.flatnonzero(bad)[0])
            return k, i, float(v[k])
    return None


def layout(mod: types.ModuleType) -> tuple:
    """Angle names and mounting names of a stand module (one mounting: ('+x+y+z',))."""
    return list(mod.ANGLES), list(mod.MOUNTINGS)


def H_at(mod, angles_rad, mounts=None, variables=()):
    """H at positions: angles (S, n_angles) in radians, mounts (S,) indices, and the values (S,) of the
    model's VARIABLES (time, temperature) -> (3, m, S)."""
    import numpy as np
    angles_rad = np.atleast_2d(np.asarray(angles_rad, float))
    cols = [angles_rad[:, i] for i in range(angles_rad.shape[1])] + [np.asarray(v, float) for v in variables]
    return mod.H(*cols, mount=0 if mounts is None else np.asarray(mounts))


def q_of(mod: types.ModuleType, physical) -> numpy.ndarray:
    """The q (4) of 000 an estimate bounds for a unit with these physical errors: those of the unit that
    reads the same with the model's ABSORBED parameters at 0 (`equivalent`; the unit itself when none)."""
    import numpy as np
    physical = np.asarray(physical, float)
    same = mod.equivalent(physical)
    return np.asarray(mod.PHYSICAL_TO_Q, float) @ same
