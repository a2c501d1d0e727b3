"""Context of the derivation report: every derived expression beside the published one."""
from fractions import Fraction

import sympy as sp

from . import published
from .model import Link
from .printer import linear_text


def _latex(expr, model):
    names = {p.symbol: p.latex for p in model.parameters}
    names.update({a.symbol: a.latex for a in model.stand.angles})
    return sp.latex(sp.sympify(expr), symbol_names=names)


def _linear_latex(coeffs, model):
    """A linear combination in the preferred order, leading term first, with LaTeX names."""
    by_name = dict(zip((p.name for p in model.parameters), coeffs))
    latex = {p.name: p.latex for p in model.parameters}
    return linear_text([by_name[n] for n in model.preferred], [latex[n] for n in model.preferred])


def _parse(text, model):
    local = {p.name: p.symbol for p in model.parameters}
    local.update({a.name: a.symbol for a in model.stand.angles})
    return sp.sympify(text, locals=local)


def _link_latex(link: Link, model):
    s = {p.name: p.latex for p in model.parameters}
    a = {x.name: x.latex for x in model.stand.angles}
    if link.angle is None:
        parts = ([sp.latex(link.fixed_deg) + r"^\circ"] if link.fixed_deg is not None else []) + (
            [s[link.error]] if link.error else [])
        arg = " + ".join(parts)
        arg = f"-({arg})" if link.sign < 0 and len(parts) > 1 else ("-" + arg if link.sign < 0 else arg)
    else:
        arg = a[link.angle] + (f" - {s[link.error]}" if link.error else "")
        if link.harmonic:
            hs, hc = (s[n] for n in link.harmonic)
            arg += rf" - {hs}\sin {a[link.angle]} - {hc}\cos {a[link.angle]}"
        arg = f"-({arg})" if link.sign < 0 else arg
    if isinstance(link.axis, int):
        return rf"C_{link.axis}({arg})"
    axis = r",\ ".join(f"{float(sp.N(v, 12)):.6g}" for v in link.axis)       # the unit vector, rounded for reading
    return rf"C_{{({axis})}}({arg})"


def _aligned_published_H(printed, derived, parse):
    """Printed rows padded where a zero was lost; returns (rows, notes on each padding)."""
    rows, notes = [], []
    for p, row in enumerate(printed):
        row = list(row)
        if len(row) < len(derived[p]):
            fits = [k for k in range(len(row) + 1)
                    if all(sp.expand(parse(x) - y) == 0 for x, y in
                           zip(row[:k] + ["0"] + row[k:], derived[p]))]
            notes.append(f"H^({p + 1}) is printed with {len(row)} entries; inserting the lost 0 at "
                         f"position {', '.join(str(k + 1) for k in fits) or 'none'} (1-based) "
                         "reproduces the derived vector" if fits else
                         f"H^({p + 1}) is printed with {len(row)} entries and no single lost 0 explains it")
            k = fits[0] if fits else len(row)
            row = row[:k] + ["(lost 0)"] + row[k:]
        rows.append(row)
    return rows, notes


def _estimator_text(terms):
    return " ".join(f"{'+' if w >= 0 else '-'} {abs(w)} z{p}({a}, {b})" for w, p, a, b in terms)


def report_context(d):
    """Template context of the derivation report of the stand of 000: derived beside printed."""
    m, ident = d.model, d.ident
    derived_H = [list(ident.H.row(p)) for p in range(ident.H.rows)]
    printed_H, h_notes = _aligned_published_H(published.H_000, derived_H, lambda t: _parse(t, m))
    H_rows = []
    for nu in range(ident.H.cols):
        cells = []
        for p in range(ident.H.rows):
            pub = printed_H[p][nu]
            same = pub != "(lost 0)" and sp.simplify(_parse(pub, m) - ident.H[p, nu]) == 0
            cells.append((_latex(ident.H[p, nu], m), pub if pub == "(lost 0)" else
                          _latex(_parse(pub, m), m), "yes" if same else "**no**"))
        H_rows.append((nu + 1, cells))
    syms = [p.symbol for p in m.parameters]
    q_rows = []
    for nu in range(ident.R.rows):
        q = sum(c * s for c, s in zip(ident.R.row(nu), syms))
        pub = _parse(published.Q_000[nu], m)
        pub_coeffs = [pub.coeff(s) for s in syms]
        q_rows.append((nu + 1, _linear_latex(list(ident.R.row(nu)), m), _linear_latex(pub_coeffs, m),
                       "yes" if sp.expand(q - pub) == 0 else "**no**"))
    null_rows = [_linear_latex(list(v), m) for v in ident.null_space]
    est_rows = []
    for nu, psi in enumerate(d.estimators):
        ours = [(Fraction(int(w.p), int(w.q)), p + 1, *m.plan_deg[s]) for (s, p), w in sorted(psi.items())]
        pub = [(Fraction(w), p, a, b) for w, p, a, b in published.ESTIMATORS_000[f"q{nu + 1}"]]
        same = sorted(ours) == sorted(pub)
        est_rows.append((nu + 1, _estimator_text(ours), sum(abs(t[0]) for t in ours),
                         _estimator_text(pub), sum(abs(t[0]) for t in pub), "yes" if same else "no"))
    counts = {"stand": len(m.stand.parameters), "block": len(m.block.parameters)}
    return dict(
        title=m.stand.title, source=m.stand.source, model=m,
        chain=" ".join(_link_latex(link, m) for link in m.stand.chain),
        theta=", ".join(_latex(sp.Symbol(n), m) for n in m.stand.theta),
        up_nominal=_latex(d.up_nominal[0], m), H_rows=H_rows, h_notes=h_notes, q_rows=q_rows,
        null_rows=null_rows, free=[{p.name: p.latex for p in m.parameters}[n] for n in ident.free],
        counts=counts, n_params=len(syms), rank=ident.R.rows, est_rows=est_rows,
        plan=m.plan_deg,
    )


def stand_report_context(d):
    """Context of the report of a stand with no published results: what the derivation found."""
    m, ident = d.model, d.ident
    syms = [p.symbol for p in m.parameters]
    H_rows = [(k, name, [(nu + 1, [_latex(ident.H[3 * k + p, nu], m) for p in range(3)])
                         for nu in range(ident.H.cols)]) for k, name in enumerate(m.mountings)]
    return dict(
        title=m.stand.title, source=m.source_file, model=m,
        chain=" ".join(_link_latex(link, m) for link in m.stand.chain),
        H_rows=H_rows, rank=ident.R.rows, n_params=len(syms),
        q_rows=[(nu + 1, _linear_latex(list(ident.R.row(nu)), m)) for nu in range(ident.R.rows)],
        null_rows=[_linear_latex(list(v), m) for v in ident.null_space],
        free=[{p.name: p.latex for p in m.parameters}[n] for n in ident.free])
