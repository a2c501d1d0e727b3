"""Optimality certificates, checkable without trusting any solver.

A certificate claims that the optimal guaranteed error of a^T q over a whole continuum of positions
(a box of stand angles, or the unit sphere of 001) equals a value v. It carries the measurement
functions H as exact expressions, a primal estimator (positions, components, weights) and a dual
vector lambda, all exact (rationals, or algebraic numbers like sqrt(3)/2). The check:
(a) unbiasedness: sum_k w_k H^(p_k)(x_k) = a, exactly;
(b) value: sum_k |w_k| = a^T lambda = v, exactly;
(c) dual feasibility: |H^(p)(x)^T lambda| <= 1 for every x of the continuum and every p: exactly
    when the trigonometric form gives it (sum of |coefficients| of canonical monomials <= 1), else by
    rigorous interval branch and bound, which proves it to 1 + ETA.
By weak duality (a)-(c) prove v/(1 + ETA) <= optimum <= v (= v when (c) closes exactly). A plan's
certificate (`garant plan --certificates`) has a finite domain, the positions the plan was chosen
from, each checked to be one the stand can take; (c) is then exact at each of them.
Before (a), step (0) ties the certificate to its model: its H and domain must be those re-derived
from the model it names (reference.py), and its target the e_nu of the q its claim names. Every
string is read by the whitelist grammar of parse.py and every list is size-capped: a hostile file
is refused with one line, never evaluated.
"""
import re
import json
from fractions import Fraction

import numpy as np
import sympy as sp

from ..solve.interval import mean_value_enclosure
from .parse import GRAMMAR_NAMES, exact
from .reference import definitions, reference

ETA = 1e-9
FORMAT = "garant-certificate-1"
MAX_ITEMS = 10_000           # rows, entries, primal terms, dual entries
MAX_BOX_ANGLES = 4           # interval branch and bound starts from 8^n boxes
MAX_BYTES = 2_000_000


class MalformedCertificate(ValueError):
    """A certificate file that is not of the garant-certificate-1 form."""


def as_exact(x):
    """x as an exact SymPy number: exact input is kept as it is (no search), a Fraction becomes a
    Rational, and only a float is identified (nsimplify)."""
    if isinstance(x, Fraction):
        return sp.Rational(x.numerator, x.denominator)
    if isinstance(x, (int, np.integer)):
        return sp.Integer(int(x))
    if isinstance(x, sp.Basic) and not x.atoms(sp.Float):
        return x
    return sp.nsimplify(x)


def _s(x):
    return sp.sstr(as_exact(x))


def make(model, claim, domain, H_rows, target, value, primal, dual):
    """A certificate as a JSON-ready dict. H_rows: list of rows (one per component and mounting) of
    expression strings; primal: (position strings, row index, weight); dual: exact numbers."""
    return {"format": FORMAT, "model": model, "claim": claim, "domain": domain, "H": H_rows,
            "target": [_s(a) for a in target], "value": _s(value),
            "primal": [{"at": list(at), "row": int(row), "weight": _s(w)} for at, row, w in primal],
            "dual": [_s(y) for y in dual]}


def _list(value, where, length=None):
    if not isinstance(value, list) or not value or len(value) > MAX_ITEMS:
        raise MalformedCertificate(f"{where}: expected a list of 1 to {MAX_ITEMS} items")
    if length is not None and len(value) != length:
        raise MalformedCertificate(f"{where}: expected {length} items, found {len(value)}")
    return value


def _field(cert, key, kind):
    if not isinstance(cert.get(key), kind):
        raise MalformedCertificate(f"{key!r}: missing or not a {kind.__name__}")
    return cert[key]


def _exact(text, syms, where):
    try:
        return exact(text, syms)
    except ValueError as e:
        raise MalformedCertificate(f"{where}: {e}") from None


def parsed(cert):
    """The certificate's content as exact SymPy objects, after checking its form and sizes."""
    if not isinstance(cert, dict):
        raise MalformedCertificate(f"expected a JSON object, found {type(cert).__name__}")
    dom = _field(cert, "domain", dict)
    if dom.get("kind") not in ("angles", "sphere", "positions"):
        raise MalformedCertificate(f"domain.kind: {dom.get('kind')!r} is not 'angles', 'sphere' or 'positions'")
    names = _list(dom.get("names"), "domain.names")
    if not all(isinstance(n, str) and re.fullmatch(r"[A-Za-z][A-Za-z0-9_]{0,40}", n) for n in names) \
            or len(set(names)) != len(names) or len(names) > 12:
        raise MalformedCertificate("domain.names: at most 12 distinct plain names")
    if set(names) & GRAMMAR_NAMES:
        raise MalformedCertificate(f"domain.names: {sorted(set(names) & GRAMMAR_NAMES)[0]!r} is a constant or "
                                   "function of the expression grammar, not an angle name")
    syms = [sp.Symbol(n, real=True) for n in names]
    H = [[_exact(e, syms, f"H[{i}][{j}]") for j, e in enumerate(_list(row, f"H[{i}]"))]
         for i, row in enumerate(_list(cert.get("H"), "H"))]
    m = len(H[0])
    if any(len(row) != m for row in H):
        raise MalformedCertificate("H: rows of different lengths")
    a = [_exact(x, (), f"target[{k}]") for k, x in enumerate(_list(cert.get("target"), "target", m))]
    lam = [_exact(x, (), f"dual[{k}]") for k, x in enumerate(_list(cert.get("dual"), "dual", m))]
    v = _exact(cert.get("value"), (), "value")
    primal = []
    for k, term in enumerate(_list(cert.get("primal"), "primal")):
        if not isinstance(term, dict) or not isinstance(term.get("row"), int) or not 0 <= term["row"] < len(H):
            raise MalformedCertificate(f"primal[{k}]: needs 'at', 'weight' and a 'row' below {len(H)}")
        at = {s: _exact(x, (), f"primal[{k}].at") for s, x in zip(syms, _list(term.get("at"), f"primal[{k}].at",
                                                                              len(syms)))}
        primal.append((at, term["row"], _exact(term.get("weight"), (), f"primal[{k}].weight")))
    ranges = positions = None
    if dom["kind"] == "positions":                     # a finite set of positions: the plan's candidates
        positions = [[_exact(x, (), f"domain.positions[{k}]") for x in _list(p_, f"domain.positions[{k}]", len(syms))]
                     for k, p_ in enumerate(_list(dom.get("positions"), "domain.positions"))]
    if dom["kind"] == "angles":
        ranges = [[_exact(x, (), "domain.ranges") for x in _list(r, "domain.ranges[]", 2)]
                  for r in _list(dom.get("ranges"), "domain.ranges", len(syms))]
    return dict(syms=syms, H=H, a=a, lam=lam, v=v, primal=primal, ranges=ranges, positions=positions)


def tied_to_model(cert, c, base=None):
    """(passed, detail): H and domain are those of the model the certificate names (a description
    file: the very file, by its SHA-256), and the target is the e_nu of the q its claim names."""
    import hashlib

    from .reference import stand_file
    if not isinstance(cert.get("model"), str):
        return False, "names no model"
    try:
        path = stand_file(cert["model"], base)
        if path is not None and hashlib.sha256(path.read_bytes()).hexdigest() != cert.get("model_sha256"):
            return False, f"{cert['model']} is not the description the certificate was made for (SHA-256 differs)"
        H_ref, dom_ref, q_names = reference(cert["model"], base)
        defs = definitions(cert["model"], base)
    except ValueError as e:
        return False, str(e)
    kind = cert["domain"]["kind"]
    if [str(s) for s in c["syms"]] != dom_ref["names"]:
        return False, (f"domain angles {cert['domain'].get('names')} are not those of {cert['model']} "
                       f"({dom_ref['names']})")
    if kind != dom_ref["kind"] and kind != "positions":
        return False, f"domain kind {kind!r} is not that of {cert['model']} ({dom_ref['kind']!r})"
    if kind == "angles" and c["ranges"] != [[exact(x) for x in r] for r in dom_ref["ranges"]]:
        return False, "the domain is not the whole box of angles of the model"
    if kind == "positions" and "detents_deg" not in dom_ref:
        return False, f"a finite domain is not one of {cert['model']}'s (its domain is the {dom_ref['kind']})"
    if kind == "positions":
        bad = _unreachable(c["positions"], dom_ref) or _missing(c["positions"], cert["domain"], dom_ref)
        if bad:
            return False, bad
    bad = _claim_mismatch(cert, c, q_names) or _definition_mismatch(cert, q_names, defs)
    if bad:
        return False, bad
    syms = {s.name: s for s in c["syms"]}
    ref = [[e.subs({x: syms[x.name] for x in e.free_symbols}) for e in row] for row in H_ref]
    if len(ref) != len(c["H"]) or len(ref[0]) != len(c["H"][0]):
        return False, f"H is {len(c['H'])} x {len(c['H'][0])}; {cert['model']} has {len(ref)} x {len(ref[0])}"
    for i, (row, row_ref) in enumerate(zip(c["H"], ref)):
        for j, (h, r) in enumerate(zip(row, row_ref)):
            if sp.expand(h - r) != 0:
                return False, f"H[{i}][{j}] = {h} differs from the model's {r}"
    q = re.search(r"\bof (\S+) ", str(cert.get("claim", "")))
    nu = q_names.index(q.group(1)) if q and q.group(1) in q_names else -1
    if nu < 0 or c["a"] != [int(k == nu) for k in range(len(c["a"]))]:
        return False, "the target is not e_nu of the q the claim names"
    return True, f"H and domain re-derived from {cert['model']}; target e_{nu + 1} ({q_names[nu]})"


def _degrees(x):
    """An exact angle (radians) in degrees, exactly: a rational number of degrees, or None. No float and
    no identification (nsimplify) is involved: pi/2 (1 + 10^-15) is 90.00000000000009 degrees, not 90."""
    deg = sp.expand(x * 180 / sp.pi)
    return deg if deg.is_Rational else None


def _unreachable(positions, dom_ref):
    """Why a position of the certificate is not one the stand can take, or None."""
    for k, pos in enumerate(positions):
        for i, x in enumerate(pos):
            deg = _degrees(x)
            if deg is None:
                return f"position {k + 1}: {x} is not a rational number of degrees"
            det = dom_ref["detents_deg"][i]
            lo, hi = dom_ref["ranges_deg"][i]
            if det and not any((deg - sp.Rational(str(d))) % 360 == 0 for d in det):
                return f"position {k + 1}: {deg} degrees is not a detent of the stand"
            if not det and not any(lo <= deg + t <= hi for t in (-360, 0, 360)):
                return f"position {k + 1}: {deg} degrees is outside the range [{lo}, {hi}]"
    return None


#: The claim a certificate may make, by domain kind: anything else (another domain's words, control
#: characters, text after the claim) is refused, so a file cannot relabel what it proves.
CLAIM = re.compile(r"optimal guaranteed error of (\S+)( = [A-Za-z0-9_ +\-*/().^]{1,300})? on (.{1,120})")


def _claim_suffix(cert, c):
    kind = cert["domain"]["kind"]
    if kind == "angles":
        return "the whole box of angles"
    if kind == "sphere":
        return "the unit sphere (units of delta_sigma_max)"
    return f"the {len(c['positions'])} candidate positions of the plan search"


def _claim_mismatch(cert, c, q_names):
    """Why the certificate's claim is not the one its domain allows, or None."""
    claim = cert.get("claim")
    m = CLAIM.fullmatch(claim) if isinstance(claim, str) else None
    if m is None or m.group(1) not in q_names:
        return "the claim is not of the form 'optimal guaranteed error of <q> = <definition> on <domain>'"
    want = _claim_suffix(cert, c)
    if m.group(3) != want:
        return f"the claim says 'on {m.group(3)}' but the domain is {want}"
    return None


def _definition_mismatch(cert, q_names, defs):
    """Why the definition the claim states for its q is not the one the model derives (compared exactly, after
    parsing both by the whitelist grammar), or None. The norm model's claims state none."""
    m = CLAIM.fullmatch(cert["claim"])
    q, stated = m.group(1), m.group(2)
    if defs is None:
        return f"the claim states a definition of {q}, which {cert['model']}'s claims do not" if stated else None
    if not stated:
        return f"the claim states no definition of {q}"
    want = defs[q_names.index(q)]
    try:
        got = exact(stated[3:], sorted(want.free_symbols | _names(stated[3:]), key=str))
    except (MalformedCertificate, ValueError):
        return f"the claim's definition of {q} is not an expression in the model's parameters"
    if sp.expand(got - want) != 0:
        return f"the claim's definition {q} = {stated[3:]} is not the model's, {q} = {want}"
    return None


def _names(text):
    """Real symbols of the plain names in a definition (the parser refuses any other)."""
    return {sp.Symbol(n, real=True) for n in re.findall(r"[A-Za-z_][A-Za-z0-9_]*", text) if n not in GRAMMAR_NAMES}


def _missing(positions, dom, dom_ref):
    """Why a finite domain is not the stand's whole reachable set (every combination of detents, and on an
    angle without detents every multiple of the domain's `grid_step_deg` in its range), or None. A domain
    may hold more reachable positions (the exchange method's), never fewer: an optimum over a subset the
    file chooses is no optimum of the stand."""
    import itertools
    step = None
    if not all(dom_ref["detents_deg"]):
        try:
            step = exact(str(dom.get("grid_step_deg")))
        except ValueError:
            return "domain.grid_step_deg: the grid step (degrees) of the angles without detents is missing"
        if not (step.is_Rational and step > 0 and (360 / step).is_Integer and 360 / step <= 3600):
            return f"domain.grid_step_deg: {step} does not divide 360 degrees into at most 3600 steps"
    values = []
    for det, (lo, hi) in zip(dom_ref["detents_deg"], dom_ref["ranges_deg"]):
        if det:
            values.append({sp.Rational(str(d)) % 360 for d in det})
            continue
        lo, hi = sp.Rational(str(lo)), sp.Rational(str(hi))
        k, grid = int(sp.ceiling(lo / step)), set()
        while k * step <= hi and k * step < lo + 360:        # the plan search's grid (models.reachable_grid)
            grid.add((k * step) % 360)
            k += 1
        values.append(grid)
    if int(np.prod([len(v) for v in values])) > MAX_ITEMS:
        return f"the stand's reachable grid has more than {MAX_ITEMS} positions: no certificate covers it"
    have = {tuple(_degrees(x) % 360 for x in pos) for pos in positions}
    for want in itertools.product(*values):
        if tuple(want) not in have:
            return (f"the domain leaves out the reachable position ({', '.join(f'{float(w):g}' for w in want)}) "
                    "degrees: a certificate's positions must include the stand's whole reachable set")
    return None


def _zero(x):
    """Whether the exact number x is 0: expanded first (radicals of rationals come out canonical, so a
    zero is usually seen at once), simplified only when that does not show it."""
    return sp.expand(x) == 0 or sp.simplify(x) == 0


def check(cert, base=None):
    """[(step, passed, detail)] for the steps (0), (a), (b), (c); a certificate holds iff all pass.
    MalformedCertificate when the file is not of the certificate form. `base`: the certificate's
    folder, where a description file it names may lie."""
    if not isinstance(cert, dict) or cert.get("format") != FORMAT:
        raise MalformedCertificate(f"not a {FORMAT} certificate (no \"format\": \"{FORMAT}\")")
    c = parsed(cert)
    syms, H, a, lam, v = c["syms"], c["H"], c["a"], c["lam"], c["v"]
    m = len(H[0])
    out = [("(0) model", *tied_to_model(cert, c, base))]
    if not out[0][1]:
        return out
    if cert["domain"]["kind"] == "sphere":               # the estimator's directions are unit vectors, exactly
        for at, _, _ in c["primal"]:
            if not _zero(sum((at[x] ** 2 for x in syms), sp.Integer(0)) - 1):
                out.append(("(a) unbiased", False, f"a primal position, ({', '.join(str(at[x]) for x in syms)}), "
                                                   "is off the unit sphere"))
                return out
    image = [sp.Integer(0)] * m
    for at, row, w in c["primal"]:
        image = [sp.expand(i + w * h.subs(at)) for i, h in zip(image, H[row])]
    bad = [(k, i, t) for k, (i, t) in enumerate(zip(image, a)) if not _zero(i - t)]
    out.append(("(a) unbiased", not bad, "sum w H = a exactly" if not bad else
                f"component {bad[0][0] + 1} of sum w H is {bad[0][1]}, the target has {bad[0][2]}"))
    l1 = sum((abs(w) for _, _, w in c["primal"]), sp.Integer(0))
    dual_value = sp.expand(sum((x * y for x, y in zip(a, lam)), sp.Integer(0)))
    ok = _zero(l1 - v) and _zero(dual_value - v)
    out.append(("(b) primal = dual = value", ok, f"sum|w| = {l1}, a.lambda = {dual_value}, value = {v}"))
    if cert["domain"]["kind"] == "positions":
        out.append(("(c) dual feasible",) + feasible_at(H, lam, syms, c["positions"]))
        for at, _, _ in c["primal"]:                          # the estimator uses candidate positions only
            if [at[s] for s in syms] not in c["positions"]:
                out[-1] = ("(c) dual feasible", False, "a primal position is not among the domain's positions")
                break
    else:
        out.append(("(c) dual feasible",) + feasible(H, lam, cert["domain"], syms, c["ranges"]))
    return out


def _feasible_in_field(polys, syms, positions):
    """feasible_at in Q(sqrt2, sqrt3) arithmetic (solve/field.py), when the positions are multiples of
    15 degrees and the expressions live there; None otherwise (then SymPy decides)."""
    from ..solve import field
    try:
        degs = [[_degrees(v) for v in pos] for pos in positions]
        if not all(d is not None and d.is_Integer for pos in degs for d in pos):
            return None
        f = field.evaluator(polys, syms)
        touching = 0
        for k, pos in enumerate(degs):
            for r, v in enumerate(f([int(d) for d in pos])):
                a = abs(v)
                if a > 1:
                    return False, f"position {k + 1}, row {r}: |H^T lambda| = {float(a):.8g} > 1 (exact)"
                touching += a == 1
        return True, f"exact at all {len(positions)} positions x {len(polys)} rows ({touching} touch 1)"
    except ValueError:
        return None


def feasible_at(H, lam, syms, positions):
    """|H^(p)(x)^T lambda| <= 1 at each of finitely many positions, every row: exactly (a touching
    value is shown equal to 1 by its minimal polynomial; any other is separated from 1 numerically
    with 50 digits, far beyond its distance from 1)."""
    x = sp.Symbol("x")
    touching = 0
    polys = [sum((y * h for y, h in zip(lam, row) if y != 0), sp.Integer(0)) for row in H]
    fast = _feasible_in_field(polys, syms, positions)
    if fast is not None:
        return fast
    for k, pos in enumerate(positions):
        at = dict(zip(syms, pos))
        for r, p in enumerate(polys):
            d = sp.expand(1 - sp.expand_trig(p.subs(at)) ** 2)
            if d == 0 or sp.minimal_polynomial(d, x) == x:
                touching += 1
                continue
            val = d.evalf(50)
            if not val.is_real or val < sp.Float("1e-40", 50):
                return False, f"position {k + 1}, row {r}: |H^T lambda| = {sp.sqrt(1 - val).evalf(8)} > 1"
    return True, f"exact at all {len(positions)} positions x {len(H)} rows ({touching} touch 1)"


def feasible(H, lam, dom, syms, ranges=None, max_boxes=1_500_000):
    """|H^T lambda| <= 1 on the whole domain: (passed, detail)."""
    polys = [sp.expand(sum((y * h for y, h in zip(lam, row) if y != 0), sp.Integer(0))) for row in H]
    if dom["kind"] == "angles":
        from garant.derive.combinations import trig_basis
        sup = max(sum((abs(c) for c in trig_basis(p, syms).values()), sp.Integer(0)) for p in polys)
        if sup <= 1:
            return True, f"exact: every |H^T lambda| <= {sup} (sum of |coefficients| of canonical monomials)"
        if all(harmonic_bound(p, syms) for p in polys):
            return True, ("exact: each H^T lambda is A cos x + B sin x in one angle x, with A^2 + B^2 <= 1 "
                          "(sum of |coefficients|, or 1 - A^2 - B^2 a sum of even powers)")
        if len(syms) > MAX_BOX_ANGLES:
            return False, f"interval branch and bound covers at most {MAX_BOX_ANGLES} angles, not {len(syms)}"
        ranges = ranges or [[exact(x) for x in r] for r in dom["ranges"]]
        lo, hi = [float(r[0]) for r in ranges], [float(r[1]) for r in ranges]
        etas = []
        for k, p in enumerate(polys):
            for eta in (ETA, 1e-6):
                ok, detail = box_bound(p, syms, lo, hi, eta=eta, max_boxes=max_boxes)
                if ok or "not closed" not in detail:
                    break
            if not ok:
                return False, f"row {k}: {detail}"
            etas.append(eta)
        return True, f"interval branch and bound over the box: |H^T lambda| <= 1 + {max(etas):g}"
    if dom["kind"] == "sphere":
        from ..solve.sphere import prove_terms
        for k, p in enumerate(polys):
            terms = [(float(c), m) for m, c in sp.Poly(p, *syms).terms()]
            ok, boxes, _ = prove_terms(terms, eta=ETA)
            if not ok:
                return False, f"row {k}: |H^T lambda| exceeds 1 + {ETA:g} somewhere on the sphere"
        return True, f"interval branch and bound over the sphere: |H^T lambda| <= 1 + {ETA:g}"
    return False, f"unknown domain {dom['kind']!r}"


def harmonic_bound(p, syms):
    """Exact proof of |p| <= 1 when p = A cos x + B sin x in some angle x (A, B free of x) and the
    coefficient bound shows A^2 + B^2 <= 1 (Cauchy-Schwarz: |A cos x + B sin x| <= sqrt(A^2 + B^2))."""
    from garant.derive.combinations import trig_basis
    if p == 0:
        return True
    for x in syms:
        expanded = sp.expand(p)
        A = sp.expand(expanded.coeff(sp.cos(x)))
        B = sp.expand(expanded.coeff(sp.sin(x)))
        rest = sp.expand(expanded - A * sp.cos(x) - B * sp.sin(x))
        if (rest != 0 or x in (A.free_symbols | B.free_symbols) or A.has(sp.cos(x), sp.sin(x))
                or B.has(sp.cos(x), sp.sin(x))):
            continue
        q = sp.expand(A**2 + B**2)
        if sum((abs(v) for v in trig_basis(q, syms).values()), sp.Integer(0)) <= 1 or nonnegative(1 - q):
            return True
    return False


def nonnegative(expr):
    """Exact: expr simplifies to a sum of terms, each a positive number times even powers."""
    e = sp.factor(sp.trigsimp(sp.expand(expr)))
    if e == 0:
        return True
    for term in (e.args if e.is_Add else (e,)):
        coeff, factors = term.as_coeff_mul()
        if coeff <= 0 or not all(f.is_Pow and f.exp.is_even for f in factors):
            return False
    return True


def box_bound(expr, syms, lo, hi, eta=ETA, max_boxes=1_500_000, start=8):
    """Prove |expr| <= 1 + eta over the box by branch and bound (mean-value form); or find a point."""
    f = sp.lambdify(syms, expr, modules=[{"sin": lambda x: x.sin(), "cos": lambda x: x.cos()}])
    n = len(syms)
    edges = [np.linspace(a, h, start + 1) for a, h in zip(lo, hi)]
    grids = np.meshgrid(*[e[:-1] for e in edges], indexing="ij")
    los = [g.ravel() for g in grids]
    w = [np.full(los[0].shape, (h - a) / start) for a, h in zip(lo, hi)]
    evaluated = 0
    while los[0].size:
        evaluated += los[0].size
        if evaluated > max_boxes:
            return False, f"not closed within {max_boxes} boxes"
        bounds = [x for i in range(n) for x in (los[i], los[i] + w[i])]
        enc = mean_value_enclosure(lambda *v: _as_grad(f(*v), v[0]), *bounds)
        from ..solve.interval import box_variables
        c = [los[i] + w[i] / 2 for i in range(n)]
        at_c = _as_grad(f(*box_variables(c, c)), None).v
        viol = np.minimum(np.abs(at_c.lo), np.abs(at_c.hi)) > 1 + eta
        if viol.any():
            k = int(np.flatnonzero(viol)[0])
            where = ", ".join(f"{s}={c[i][k]:.6g}" for i, s in enumerate(syms))
            return False, f"|H^T lambda| = {max(abs(at_c.lo[k]), abs(at_c.hi[k])):.6g} > 1 at {where}"
        bad = enc.mag() > 1 + eta
        if not bad.any():
            return True, f"{evaluated} boxes"
        if np.any(bad & (w[0] < 1e-9)):
            return False, "boxes too small without closing (a touching point with zero curvature?)"
        keep = np.flatnonzero(bad)
        los = [x[keep] for x in los]
        w = [x[keep] / 2 for x in w]
        for i in range(n):                              # split every box in 2^n
            los = [np.concatenate([x, x + (w[i] if j == i else 0)]) for j, x in enumerate(los)]
            w = [np.concatenate([x, x]) for x in w]
    return True, f"{evaluated} boxes"


def _as_grad(value, like):
    """lambdify returns a plain number for constant expressions: lift it to an interval Grad."""
    from ..solve.interval import Grad, Iv
    if isinstance(value, Grad):
        return value
    ref = like.v.lo if like is not None else np.zeros(1)
    zero = Iv(np.zeros_like(ref))
    n = len(like.d) if like is not None else 0
    return Grad(Iv(np.full_like(ref, float(value))), [zero] * n)


def write(cert, path):
    """Write a certificate as JSON (atomically)."""
    from ..io.report import write_text
    write_text(path, json.dumps(cert, indent=1) + "\n")


def _json_int(text):
    """A JSON integer of at most 40 digits (exact numbers are strings of the grammar; row indices small)."""
    if len(text.lstrip("-")) > 40:
        raise ValueError(f"an integer of {len(text.lstrip('-'))} digits (at most 40)")
    return int(text)


def read(path):
    """The JSON of a certificate file; MalformedCertificate if it is not JSON or is too large or deep."""
    from ..io import files
    why = files.problem(path, "the certificate", MAX_BYTES)
    if why:
        raise MalformedCertificate(why)
    with open(path, "rb") as fh:
        data = fh.read(MAX_BYTES + 1)
    if len(data) > MAX_BYTES:
        raise MalformedCertificate(f"larger than {MAX_BYTES} bytes")
    try:
        cert = files.json_text(data.decode("utf-8"), parse_int=_json_int)
    except (UnicodeDecodeError, json.JSONDecodeError) as e:
        raise MalformedCertificate(f"not JSON ({e})") from None
    except ValueError as e:
        raise MalformedCertificate(str(e)) from None
    except RecursionError:
        raise MalformedCertificate("JSON nested too deep") from None
    from ..errors import DataError
    from ..io import schemas
    try:                                   # the published form first (docs/schemas/), then the exact content
        schemas.validate(cert, "certificate", "the certificate")
    except DataError as e:
        raise MalformedCertificate(str(e).removeprefix("the certificate: ")) from None
    return cert
