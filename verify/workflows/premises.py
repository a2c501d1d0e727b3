"""The premises of a guaranteed bound: what has to hold for the bound to hold, stated with the bound.

A bound of guaranteed estimation (000) holds for every truth that satisfies its premises: the noise
bound (5), a-priori bounds on the parameters the data cannot separate (and on the stand's own
errors), and the gravity the residual (1) is normalised by. Each bound used here has a source: the
stand description (`bound` of a [[parameter]]), a command-line option, or a stated default.
"""
from dataclasses import dataclass, field

import numpy as np

from ..errors import DataError, opt
from ..defaults import G_DEFAULT

#: The gravity assumed when none is given, m/s^2 (with the uncertainty G_UNCERTAINTY_DEFAULT).
#: Defaults where the description states no bound (rad, or dimensionless).
STAND_BOUND = 1e-3        # a stand error of a description that states none
MOUNTING_BOUND = 1e-2     # the block on its fixture, rad (about 0.6 degree)
BLOCK_BOUND = 0.1         # scale factors and misalignments (10 %): only starts the a posteriori iteration
#: Delta_g/g when --g is not given: 9.81 m/s^2 is off by up to 3.0e-3 relative at sea level (9.780 at the
#: equator, 9.832 at the poles) and by 4.6e-3 at 5 km altitude on the equator.
G_UNCERTAINTY_DEFAULT = 5e-3
#: Delta_g/g with a local --g (a gravity model with the latitude and height of the stand: about 10 mGal).
G_UNCERTAINTY_LOCAL = 1e-5
NEAR_EDGE = 0.9           # an estimate plus its bound beyond this fraction of what the a-priori bounds allow is said


@dataclass(frozen=True)
class Premises:
    """What a printed bound assumes: |rho| <= sigma (its source), g, and |p_k| <= bounds[k] for every
    physical parameter (inf where none is needed: a bias enters the readings linearly)."""

    sigma: float
    sigma_source: str
    g: float
    g_uncertainty: float
    g_source: str
    names: tuple
    kinds: tuple
    bounds: np.ndarray
    sources: tuple
    absorbed: tuple = ()     # parameters the block absorbs exactly (the model's ABSORBED): bound 0, no premise
    split: dict = field(default_factory=dict)   # their bounds (value, source): a premise only of splitting them
                                                # from Gamma again (the block's physical errors, (29) of 000)
    turned: dict = field(default_factory=dict)  # the stated bounds (value, source) of the mounting an absorbed
                                                # turn leaves, where `bounds` holds the equivalent unit's

    def physical(self):
        """The a-priori bound of each physical parameter of the unit itself, as stated: `bounds` where nothing
        is absorbed, else the bound an absorbed parameter would have (`split`) or the stated one (`turned`)."""
        return np.array([(self.split.get(n) or self.turned.get(n) or (b,))[0] for n, b in zip(self.names, self.bounds)])

    def statement(self):
        """One line: the bounds hold if ..."""
        groups = {}
        for name, kind, b, src in zip(self.names, self.kinds, self.bounds, self.sources):
            if kind not in ("bias", "gravity") and name not in self.absorbed:
                groups.setdefault((float(b), src), []).append(name)
        parts = [f"every residual component of (5) is within sigma = {self.sigma:g} ({self.sigma_source})"]
        if not any(k == "gravity" and n in self.absorbed for n, k in zip(self.names, self.kinds)):
            parts.append(f"|Delta_g/g| <= {self.g_uncertainty:g}: the true g within that of g = {self.g:g} m/s^2 "
                         f"({self.g_source})")
        parts += [f"|{', '.join(n)}| <= {b:g} ({src})" for (b, src), n in groups.items()]
        return "the bounds hold if " + "; ".join(parts)

    def meaning(self):
        """One line: what the bounded q are when the block absorbs parameters (empty when it absorbs none)."""
        if not self.absorbed:
            return ""
        gravity = [n for n, k in zip(self.names, self.kinds) if k == "gravity" and n in self.absorbed]
        offset = [n for n, k in zip(self.names, self.kinds) if k == "stand" and n in self.absorbed]
        mount = [n for n, k in zip(self.names, self.kinds) if k == "mounting" and n in self.absorbed]
        if not offset:
            how = "absorbed into Gamma exactly"
        elif not self.turned:
            how = (f"absorbed into Gamma exactly, the encoder offset {', '.join(offset)} of the instrument-side axis "
                   "as one more fixed turn beside the mounting")
        else:
            how = (f"{mount[0]} taken by the offset {offset[0]}, and that by a turn about the mountings' common axis "
                   "that Gamma and the mounting take, exactly")
        out = (f"The bounded q are those of the unit that reads the same with {', '.join(self.absorbed)} = 0, "
               f"{how} (no data tell the two apart)")
        if gravity:
            out += (f": scale factors relative to g = {self.g:g} m/s^2 (the true g within {self.g_uncertainty:g} of "
                    f"it, {self.g_source})")
        if len(self.absorbed) > len(gravity):
            out += ", misalignments to the stand's axes (the mounting included)"
        return out

    def to_dict(self):
        """The premises as the JSON results carry them: statement, meaning, each bound and its source."""
        return {"statement": self.statement(), "meaning": self.meaning(), "absorbed": list(self.absorbed),
                "split": {n: {"bound": b, "source": src} for n, (b, src) in self.split.items()},
                "turned": {n: {"bound": b, "source": src} for n, (b, src) in self.turned.items()},
                "sigma": self.sigma, "sigma_source": self.sigma_source,
                "g": self.g, "g_uncertainty": self.g_uncertainty, "g_source": self.g_source,
                "a_priori": {n: {"kind": k, "bound": (float(b) if np.isfinite(b) else None), "source": s}
                             for n, k, b, s in zip(self.names, self.kinds, self.bounds, self.sources)}}


def gravity_uncertainty(g_given, stated=None):
    """(bound of |Delta_g/g|, its source): the one rule of every command (estimate, calibrate-norm and the
    rest): --g-uncertainty when stated, else 1e-5 for a local --g, else 5e-3 for the assumed 9.81."""
    if stated is not None:
        return stated, "--g-uncertainty"
    if g_given:
        return G_UNCERTAINTY_LOCAL, "default for a local --g"
    return G_UNCERTAINTY_DEFAULT, f"default: g = {G_DEFAULT:g} assumed, not given"


def gravity_line(g_given, g_uncertainty, g_source):
    """The line every command prints when --g was not given (None when it was): what the assumed g costs."""
    if g_given:
        return None
    return (f"g: {G_DEFAULT:g} m/s^2 assumed (no --g), |Delta_g/g| <= {g_uncertainty:g} ({g_source}): scale factors "
            f"are relative to {G_DEFAULT:g} and the calibration saved allows for up to {g_uncertainty * G_DEFAULT:.2g} "
            f"m/s^2 at 1 g; give --g, the local gravity, for {G_UNCERTAINTY_LOCAL:g}")


def premises(mod, sigma, g, *, g_given=True, g_uncertainty=None, prior=None, sigma_source="--sigma", bound=None):
    """The premises of a model's bounds: each parameter's a-priori bound from `bound` ({name: bound}, the
    --bound NAME=VALUE of the commands), else `prior` for every stand, mounting, block and effect parameter
    when given (the override), else the description's, else the default of its kind; Delta_g/g from
    `g_uncertainty`, else the default for a stated or assumed g."""
    kinds, stated = mod.PARAMETER_KINDS, mod.PARAMETER_BOUNDS
    g_unc, g_src = gravity_uncertainty(g_given, g_uncertainty)
    default = {"stand": STAND_BOUND, "mounting": MOUNTING_BOUND, "block": BLOCK_BOUND, "effect": BLOCK_BOUND}
    absorbed = tuple(mod.ABSORBED)
    named = dict(bound or {})
    for name in named:
        if name not in mod.PARAMETER_NAMES:
            raise DataError(f"{opt('bound')} {name}: not a parameter of this model; its parameters: "
                            + ", ".join(mod.PARAMETER_NAMES))
        kind = kinds[mod.PARAMETER_NAMES.index(name)]
        if kind in ("bias", "gravity"):
            raise DataError(f"{opt('bound')} {name}: "
                            + ("a bias enters the readings linearly and needs no bound" if kind == "bias"
                               else f"bound Delta_g/g with {opt('g_uncertainty')}"))
    bounds, sources, split = [], [], {}
    for name, kind, b in zip(mod.PARAMETER_NAMES, kinds, stated):
        if kind == "bias":
            bound, src = np.inf, "none needed: enters linearly"
        elif name in named:
            bound, src = named[name], "--bound"
        elif kind == "gravity":
            bound, src = g_unc, g_src
        elif prior is not None:
            bound, src = prior, "--prior"
        elif b is not None:
            bound, src = b, "stand description"
        else:
            bound, src = default[kind], f"default for a {kind} error"
        if name in absorbed:                      # no premise of q; only splitting Gamma from it needs one
            split[name] = (float(bound), src)
            bound, src = 0.0, "absorbed into Gamma: no premise"
        elif kind == "block" and absorbed:        # the box is that of the q bounded: the equivalent unit's
            src += ", on the equivalent unit's Gamma'"
        bounds.append(bound), sources.append(src)
    turned = {}
    if mod.TURN_AXIS is not None:
        turned = _turned(mod.TURN_AXIS, list(mod.PARAMETER_NAMES), kinds, split, bounds, sources)
    return Premises(sigma=sigma, sigma_source=sigma_source, g=g, g_uncertainty=g_unc, g_source=g_src,
                    names=tuple(mod.PARAMETER_NAMES), kinds=tuple(kinds), bounds=np.array(bounds, float),
                    sources=tuple(sources), absorbed=absorbed, split=split, turned=turned)


def _turned(axis, names, kinds, split, bounds, sources):
    """The a-priori bounds of the mounting that stays when a turn about the mountings' axis n is absorbed
    (derive/model.py, `Turn`): those of the equivalent unit's theta2', theta3', set in place with their source.

    N = C3(theta3) C2(theta2) C1(theta1 - s offset) turns by at most w, the sum of the four bounds, and the
    absorbed turn R(n, a) is the root of g(a) = e3^T R N e2 nearest 0. |g(0)| = |e3 . (N e2 - e2)| <= w;
    R^T e3 runs on a circle of radius r0 = |n x e3| at unit rate, so g'(a) is within r0 (w + |a|) of
    (n x e3) . e2 = -n1 (k0 = |n1|). On [-A, A] then |g'| >= k - r0 A (k = k0 - r0 w), one sign, so g moves by at
    least A (k - r0 A) from 0 to either end; that is at least w, hence g crosses 0 there (once: |a| <= A), for
    every A between the roots of r0 A^2 - k A + w: the smaller, A = 2 w / (k + sqrt(k^2 - 4 r0 w)) (w / k0 when
    r0 = 0; below k / (2 r0), so |g'| > 0 there). The turned mounting C3(theta3') C2(theta2') = R N turns by at
    most A + w, and each of theta2', theta3' (within pi/2) by at most its turn. Returns the stated bounds
    replaced, {name: (bound, source)}."""
    n = np.asarray(axis, float)
    k0, r0 = abs(n[0]), float(np.hypot(n[0], n[1]))
    gone = [name for name in split if kinds[names.index(name)] != "gravity"]
    kept = [k for k, kind in enumerate(kinds) if kind == "mounting" and names[k] not in split]
    w = sum(split[name][0] for name in gone) + sum(bounds[k] for k in kept)
    k = k0 - r0 * w
    disc = k * k - 4 * r0 * w
    A = 2 * w / (k + np.sqrt(disc)) if k > 0 and disc >= 0 else np.inf
    if not np.isfinite(A):
        raise DataError(f"the a-priori bounds of the mounting and {', '.join(gone)} (their sum {w:g} rad) are too "
                        f"wide to bound the turn about the mountings' axis: state smaller ones (description or "
                        f"{opt('prior')})")
    given = ", ".join(f"|{names[k]}| <= {bounds[k]:g}" for k in kept)
    given += "".join(f", |{name}| <= {split[name][0]:g}" for name in gone)
    stated = {names[k]: (float(bounds[k]), sources[k]) for k in kept}
    for k in kept:
        bounds[k] = (A + w) * (1 + 1e-12)
        sources[k] = f"the equivalent unit's, turned about the mountings' axis: from {given}"
    return stated
