"""Stand descriptions in TOML, read safely: plain data, no code, every name checked.

The chain is written from the base to the table, as one builds a stand; each link is a turn about a
coordinate axis of the frame it carries (x, y, z, or -x, -y, -z): either a read angle less its
encoder offset (and optional once-per-turn harmonic), or a fixed small error. Errors raise
DescriptionError with the file and the place in it.
"""
import keyword
import math
import re
import tomllib
from pathlib import Path

from .effects import CATALOGUE, VARIABLE_DEFAULTS

from .model import Angle, Block, Link, Model, Stand
from .parameter import Parameter

AXES = {"x": 1, "y": 2, "z": 3}
KEYS = {
    "stand": {"name", "title", "source", "settle_s", "remount_s"},
    "angle": {"name", "latex", "meaning", "range_deg", "detents_deg", "speed_deg_s", "acceleration_deg_s2"},
    "parameter": {"name", "latex", "unit", "meaning", "bound"},
    "link": {"axis", "angle", "offset", "harmonic", "error", "angle_deg"},
    "block": {"misalignment", "gravity_error", "mountings"},
    "estimation": {"preferred", "plan_deg", "remount"},
}
NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]{0,31}$")
#: Limits that keep a derivation to seconds: a larger stand is refused, not left to hang.
LIMITS = {"angles": 4, "links": 12, "parameters": 40, "detents": 72, "plan positions": 200,
          "mountings": 24, "text": 300, "bytes": 1_000_000}
#: Names a description cannot give: Python's keywords, the constant and functions of the certificates'
#: expression grammar (an angle named pi would read as the constant), and the names of the block's and the
#: catalogue's own parameters and row variables (they would be declared twice). Any other name works: the
#: generated code keeps its own names apart (derive/codegen.py, code_symbols).
RESERVED = (set(keyword.kwlist) | {"pi", "sqrt", "sin", "cos"}
            | {f"Gamma{i}{j}" for i in (1, 2, 3) for j in (1, 2, 3)} | {f"bias{i}" for i in (1, 2, 3)}
            | {p.name for e in CATALOGUE.values() for p in e.params} | set(VARIABLE_DEFAULTS))


class DescriptionError(ValueError):
    """A problem in a stand description: the message names the file and the place in it."""


class Unobservable(DescriptionError):
    """Parameters the stand cannot observe to first order: `names`, and `why` in a clause (the message says more)."""

    def __init__(self, message, names, why):
        super().__init__(message)
        self.names, self.why = tuple(names), why


def _fail(path, where, msg):
    raise DescriptionError(f"{path}: {where}: {msg}")


def _keys(path, where, table, allowed):
    if not isinstance(table, dict):
        _fail(path, where, "expected a table")
    for k in table:
        if k not in allowed:
            _fail(path, where, f"unknown key {k!r} (allowed: {', '.join(sorted(allowed))})")


def _name(path, where, value):
    if not isinstance(value, str) or not NAME.match(value):
        _fail(path, where, f"{_short(value)} is not a valid name (letters, digits, _; starts with a letter; "
              "at most 32)")
    return value


def _new_name(path, where, value):
    """A name the description introduces: valid, and not one the generated code or the block uses."""
    _name(path, where, value)
    if value in RESERVED:
        _fail(path, where, f"{value!r} is reserved (a Python keyword, pi, sqrt, sin, cos, or a block or effect "
              "parameter or row variable of that name); choose another")
    return value


def _short(value):
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _text(path, where, value, default):
    """A free-text field (title, source, unit, meaning, latex): one printable line, never code."""
    if value is None:
        return default
    if not isinstance(value, str) or len(value) > LIMITS["text"] or not value.isprintable():
        _fail(path, where, f"expected one printable line of text of at most {LIMITS['text']} characters")
    return value


DECIMALS = 6        # an angle of a description is given to at most a micro-degree (no encoder resolves more)


def _degrees(path, where, v):
    """An angle in degrees as written: at most DECIMALS decimals and within +-3600 (a detent at 1e-300
    degree made certificates of 303-digit integers)."""
    r = round(v, DECIMALS)
    if abs(v) > 3600 or abs(v - r) > 1e-9 * max(1.0, abs(v)) or (v != 0 and r == 0):
        _fail(path, where, f"{_short(v)} degrees: give angles within one turn and to at most {DECIMALS} decimals")
    return r if isinstance(v, float) else v


def _is_number(v, limit=1e15):
    """A finite TOML number of magnitude below `limit` (an integer of 400 digits is refused, not converted:
    math.isfinite of it raised OverflowError)."""
    return isinstance(v, (int, float)) and not isinstance(v, bool) and (
        abs(v) < limit if isinstance(v, int) else math.isfinite(v) and abs(v) < limit)


def _numbers(path, where, value, length=None, most=None):
    if not isinstance(value, list) or not all(_is_number(v) for v in value):
        _fail(path, where, f"{_short(value)} is not a list of numbers")
    if length is not None and len(value) != length:
        _fail(path, where, f"expected {length} numbers, found {len(value)}")
    if most is not None and len(value) > most:
        _fail(path, where, f"at most {most} values")
    return value


def _bound(path, where, value):
    """An a-priori bound |parameter| <= bound (its unit): a finite number > 0 and < 1, or absent."""
    if value is None:
        return None
    if not _is_number(value) or not 0 < value < 1:
        _fail(path, where, f"{_short(value)} is not a bound: give a number > 0 and < 1 (rad, or dimensionless)")
    return float(value)


def _table_list(path, where, value, most):
    if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
        _fail(path, where, f"expected [[{where}]] tables")
    if len(value) > most:
        _fail(path, where, f"at most {most} [[{where}]] tables (a larger stand is beyond garant's limits)")
    return value


def _exact(value):
    """An exact number from a TOML number: integers as they are, decimals as the decimal written."""
    import sympy as sp
    return sp.Integer(value) if isinstance(value, int) else sp.Rational(repr(value))


def _axis(path, where, value):
    """(axis, sign): a coordinate axis (1, 2, 3) and its sign, or an exact unit vector (a tilted axis,
    the vector written normalised exactly) and +1."""
    if isinstance(value, list):
        if len(value) != 3 or not all(_is_number(v, 1e6) for v in value):
            _fail(path, where, "an axis vector needs three finite numbers")
        if not any(value):
            _fail(path, where, "an axis of zero length")
        nz = [i for i, v in enumerate(value) if v]
        if len(nz) == 1:
            return nz[0] + 1, 1 if value[nz[0]] > 0 else -1
        import sympy as sp
        v = sp.Matrix([_exact(x) for x in value])
        return tuple(sp.nsimplify(x / sp.sqrt(v.dot(v))) for x in v), 1
    if not isinstance(value, str) or value.lstrip("+-") not in AXES or len(value) > 2:
        _fail(path, where, f"{value!r} is not an axis (x, y, z, -x, -y, -z)")
    return AXES[value.lstrip("+-")], -1 if value.startswith("-") else 1


def _angle(path, where, a):
    _keys(path, where, a, KEYS["angle"])
    name = _new_name(path, f"{where}.name", a.get("name"))
    lo, hi = (_degrees(path, f"{where}.range_deg", v)
              for v in _numbers(path, f"{where}.range_deg", a.get("range_deg", [0, 360]), length=2))
    if not (lo < hi and hi - lo <= 360):
        _fail(path, f"{where}.range_deg", f"[{lo}, {hi}] is not a range of at most one turn")
    detents = [_degrees(path, f"{where}.detents_deg", v)
               for v in _numbers(path, f"{where}.detents_deg", a.get("detents_deg", []), most=LIMITS["detents"])]
    for d in detents:
        if not lo <= d <= hi:
            _fail(path, f"{where}.detents_deg", f"{d} is outside the range [{lo}, {hi}]")
    return Angle(name, _text(path, f"{where}.latex", a.get("latex"), name),
                 _text(path, f"{where}.meaning", a.get("meaning"), f"{name}, as read"), (lo, hi), tuple(detents),
                 _motion(path, f"{where}.speed_deg_s", a.get("speed_deg_s"), 1e4, "deg/s", 1e-3),
                 _motion(path, f"{where}.acceleration_deg_s2", a.get("acceleration_deg_s2"), 1e6, "deg/s^2",
                         1e-3))


def _motion(path, where, value, most, unit, least=0.0):
    """A speed, acceleration or time of the stand's motion (for `plan --route`): a number > `least` (at
    least `least` when that is not 0: a speed of 1e-3 deg/s already takes 100 hours a turn) and below
    `most` in `unit`, or absent."""
    if value is None:
        return None
    if not _is_number(value) or not (least <= value if least else 0 < value) or not value < most:
        _fail(path, where, f"{_short(value)} is not a {unit} figure: give a number "
                           f"{f'>= {least:g}' if least else '> 0'} and < {most:g}")
    return float(value)


def load(path, source_file=None):
    """Read a description file into a Model; DescriptionError on any problem."""
    path = Path(path)
    shown = source_file or str(path)
    try:
        with open(path, "rb") as fh:
            raw = fh.read(LIMITS["bytes"] + 1)
        if len(raw) > LIMITS["bytes"]:
            raise DescriptionError(f"{path}: larger than {LIMITS['bytes']} bytes; a description is a short file")
        data = tomllib.loads(raw.decode("utf-8-sig"))
    except OSError as e:
        raise DescriptionError(f"{path}: cannot read ({e.strerror})") from None
    except UnicodeDecodeError as e:
        raise DescriptionError(f"{path}: not UTF-8 text (byte {e.start})") from None
    except tomllib.TOMLDecodeError as e:
        raise DescriptionError(f"{path}: not valid TOML ({e})") from None
    except RecursionError:
        raise DescriptionError(f"{path}: nested too deep for a stand description") from None
    return from_data(data, shown)


def from_data(data, path="<description>"):
    """The Model a parsed description (a dict as TOML gives it) states; `path` names it in errors.
    Every key is checked against a whitelist and every name against the declared ones: nothing in the
    data is evaluated."""
    for k in data:
        if k not in KEYS:
            _fail(path, k, f"unknown table (allowed: {', '.join(KEYS)})")
    stand = data.get("stand", {})
    _keys(path, "stand", stand, KEYS["stand"])
    name = _name(path, "stand.name", stand.get("name"))
    angles = _angles(path, data)
    params = _parameters(path, data, angles)
    refs = _References(path, {p.name for p in params})
    links = _links(path, data, angles, refs)
    theta, dg, mounts = _block(path, data, refs)
    unused = refs.declared - refs.used
    if unused:
        _fail(path, "parameter", f"declared but used nowhere: {', '.join(sorted(unused))}")
    preferred, plan, remount = _estimation(path, data, links, refs.declared, theta, dg, len(angles))
    st = Stand(name=name, title=_text(path, "stand.title", stand.get("title"), name), angles=tuple(angles),
               chain=tuple(links[::-1]), parameters=tuple(params), theta=theta, gravity_error=dg,
               source=_text(path, "stand.source", stand.get("source"), str(path)),
               settle_s=_motion(path, "stand.settle_s", stand.get("settle_s"), 1e5, "s"),
               remount_s=_motion(path, "stand.remount_s", stand.get("remount_s"), 1e5, "s"))
    return Model(stand=st, block=Block(), preferred=tuple(preferred), plan_deg=plan,
                 remount=remount, mountings=mounts, source_file=path)


def _angles(path, data):
    """The [[angle]] tables, names unique, at least one."""
    angles = []
    for i, a in enumerate(_table_list(path, "angle", data.get("angle", []), LIMITS["angles"]), 1):
        angles.append(_angle(path, f"angle[{i}]", a))
        if angles[-1].name in {b.name for b in angles[:-1]}:
            _fail(path, f"angle[{i}].name", f"{angles[-1].name!r} is declared twice")
    if not angles:
        _fail(path, "angle", "a stand needs at least one [[angle]]")
    return angles


#: The units a stand parameter may state: the model computes angles in rad and other errors as
#: dimensionless numbers; a unit such as mrad would only relabel a value computed in rad.
UNITS = ("rad", "1")


def _parameters(path, data, angles):
    """The [[parameter]] tables, names unique among parameters and angles."""
    params = []
    for i, p in enumerate(_table_list(path, "parameter", data.get("parameter", []), LIMITS["parameters"]), 1):
        where = f"parameter[{i}]"
        _keys(path, where, p, KEYS["parameter"])
        pname = _new_name(path, f"{where}.name", p.get("name"))
        if pname in {q.name for q in params} or pname in {a.name for a in angles}:
            _fail(path, f"{where}.name", f"{pname!r} is declared twice")
        unit = _text(path, f"{where}.unit", p.get("unit"), "rad")
        if unit not in UNITS:
            _fail(path, f"{where}.unit", f"{unit!r} is not a unit the model computes in: give one of "
                                         f"{', '.join(map(repr, UNITS))} (an angle in rad, a dimensionless error "
                                         "in 1; no other unit is converted)")
        params.append(Parameter(pname, _text(path, f"{where}.latex", p.get("latex"), pname), unit,
                                _text(path, f"{where}.meaning", p.get("meaning"), pname),
                                _bound(path, f"{where}.bound", p.get("bound"))))
    return params


class _References:
    """The declared parameter names and those a link or the block refers to (to find unused ones)."""

    def __init__(self, path, declared):
        self.path, self.declared, self.used = path, declared, set()

    def __call__(self, where, value):
        _name(self.path, where, value)
        if value not in self.declared:
            _fail(self.path, where, f"parameter {value!r} is not declared in [[parameter]]")
        self.used.add(value)
        return value


def _links(path, data, angles, ref):
    """The [[link]] tables, outermost first: turning (angle, offset, harmonic) or fixed (angle_deg, error)."""
    links = []
    for i, link in enumerate(_table_list(path, "link", data.get("link", []), LIMITS["links"]), 1):
        where = f"link[{i}]"
        _keys(path, where, link, KEYS["link"])
        axis, sign = _axis(path, f"{where}.axis", link.get("axis"))
        if "angle" in link:
            if not isinstance(link["angle"], str) or link["angle"] not in {a.name for a in angles}:
                _fail(path, f"{where}.angle", f"{_short(link['angle'])} is not an [[angle]]")
            if "error" in link:
                _fail(path, where, "a link with an angle takes 'offset', not 'error'")
            harmonic = link.get("harmonic")
            if harmonic is not None and (not isinstance(harmonic, list) or len(harmonic) != 2):
                _fail(path, f"{where}.harmonic", "give two parameters [a_sin, a_cos]")
            links.append(Link(axis, link["angle"], ref(f"{where}.offset", link["offset"]) if "offset" in link else None,
                              sign, tuple(ref(f"{where}.harmonic", h) for h in harmonic) if harmonic else None))
        elif "error" in link or "angle_deg" in link:
            if "offset" in link or "harmonic" in link:
                _fail(path, where, "a fixed link takes 'angle_deg' and 'error' only")
            fixed = link.get("angle_deg")
            if fixed is not None:
                if not _is_number(fixed) or not -360 <= fixed <= 360:
                    _fail(path, f"{where}.angle_deg", f"{_short(fixed)} is not an angle in degrees within one turn")
                fixed = _exact(_degrees(path, f"{where}.angle_deg", fixed))
            links.append(Link(axis, None, ref(f"{where}.error", link["error"]) if "error" in link else None, sign,
                              fixed_deg=fixed))
        else:
            _fail(path, where, "a link needs an 'angle' (turning), an 'angle_deg' (a fixed turn such as a wedge) "
                  "or an 'error' (fixed small turn)")
    if not links:
        _fail(path, "link", "a stand needs at least one [[link]]")
    return links


def _block(path, data, ref):
    """[block]: the mounting misalignment theta (three names), Delta_g's name and the mountings."""
    block = data.get("block", {})
    _keys(path, "block", block, KEYS["block"])
    theta = block.get("misalignment")
    if not isinstance(theta, list) or len(theta) != 3:
        _fail(path, "block.misalignment", "give the three mounting-misalignment parameters")
    theta = tuple(ref(f"block.misalignment[{i}]", t) for i, t in enumerate(theta, 1))
    dg = ref("block.gravity_error", block.get("gravity_error"))
    from .remount import mountings
    mounts = block.get("mountings", ["+x+y+z"])
    if not isinstance(mounts, list) or not mounts or len(mounts) > LIMITS["mountings"]:
        _fail(path, "block.mountings", f"give a list of 1 to {LIMITS['mountings']} mountings like \"+y+z+x\"")
    for i, m in enumerate(mounts, 1):
        if not isinstance(m, str) or m not in mountings():
            _fail(path, f"block.mountings[{i}]", f"{m!r} is not a proper mounting like +x+y+z or +y+z+x")
    return theta, dg, tuple(mounts)


def _estimation(path, data, links, declared, theta, dg, n_angles):
    """[estimation]: the order q is written in (preferred), the plan of the estimators, remount."""
    est = data.get("estimation", {})
    _keys(path, "estimation", est, KEYS["estimation"])
    block_params = [p.name for p in Block().parameters]
    default = ([ln.error for ln in links if ln.error and ln.error not in theta and ln.error != dg]
               + [h for ln in links if ln.harmonic for h in ln.harmonic] + block_params + [*theta, dg])
    preferred = est.get("preferred", default)
    if not isinstance(preferred, list) or not all(isinstance(n, str) for n in preferred):
        _fail(path, "estimation.preferred", "give a list of parameter names")
    if sorted(preferred) != sorted(declared | set(block_params)) or len(set(preferred)) != len(preferred):
        missing = (declared | set(block_params)) - set(preferred)
        extra = set(preferred) - (declared | set(block_params))
        _fail(path, "estimation.preferred", f"must list every parameter once (missing: {sorted(missing)}, "
              f"unknown: {sorted(extra)})")
    plan = est.get("plan_deg", [])
    if not isinstance(plan, list) or len(plan) > LIMITS["plan positions"]:
        _fail(path, "estimation.plan_deg", f"give a list of at most {LIMITS['plan positions']} positions")
    plan = tuple(tuple(_degrees(path, f"estimation.plan_deg[{i}]", v)
                       for v in _numbers(path, f"estimation.plan_deg[{i}]", p, length=n_angles))
                 for i, p in enumerate(plan, 1))
    remount = est.get("remount", False)
    if not isinstance(remount, bool):
        _fail(path, "estimation.remount", "true or false")
    return preferred, plan, remount


def check_observable(model, J):
    """Every physical parameter must move the readings to first order; else name it and its link, or,
    for the block's own parameters, the axis the stand never turns towards gravity."""
    n = len(model.stand.chain)
    blind = [p.name for k, p in enumerate(model.parameters) if p.name.startswith("Gamma")
             and all(v == 0 for v in J.col(k))]
    if blind:
        axes = sorted({int(b[-1]) for b in blind if all(f"Gamma{i}{b[-1]}" in blind for i in (1, 2, 3))})
        why = (f"no position turns gravity onto block axis {', '.join(map(str, axes))}" if axes
               else "the positions do not vary gravity enough")
        raise Unobservable(f"{model.source_file}: the stand cannot observe the block's {', '.join(blind)}: {why}; "
                           "add a mounting that turns that axis (block.mountings, e.g. [\"+x+y+z\", \"+z+x+y\"]) "
                           "or a link that tilts it (a wedge angle other than 90 degrees, an axis not parallel)",
                           blind, why)
    for k, p in enumerate(model.parameters):
        if all(v == 0 for v in J.col(k)):
            where = next((f"link[{n - i}].{'offset' if ln.angle and ln.error == p.name else 'error'}"
                          if p.name == ln.error else f"link[{n - i}].harmonic"
                          for i, ln in enumerate(model.stand.chain) if p.name in (ln.error, *(ln.harmonic or ()))),
                         "block")
            why = (f"parameter {p.name!r} cannot be observed: the readings do not depend on it to first order (e.g. a "
                   "turn about the vertical)")
            raise Unobservable(f"{model.source_file}: {where}: {why}; remove it from the description", [p.name], why)
