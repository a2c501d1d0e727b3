"""What a certificate of a built-in model must carry, re-derived from derive/: its H rows and domain.

Both the builder and the checker take H from here, so a certificate is checked against the model it
names, never against the H it brings along.
"""
from garant.generated import MODELS as REGISTRY

from ..models import kind

#: Certificate model keys and the stand models they name (None: the norm model of 001): every built-in model.
MODELS = {name: e["module"] if e["kind"] == "stand" else None for name, e in REGISTRY.items()}


class UnknownModel(ValueError):
    """A certificate names a model garant does not know."""


def stand_file(key, base=None):
    """The description file a certificate names (as written, else beside the certificate), or None."""
    from pathlib import Path
    if not str(key).endswith(".toml"):
        return None
    for p in (Path(key), Path(base or ".") / key, Path(base or ".") / Path(key).name):
        if p.is_file():
            return p
    raise UnknownModel(f"the stand description {key!r} is not found (as written, or beside the certificate)")


def reference(key, base=None):
    """(H rows as SymPy expressions, domain dict, names of q) of the model a certificate names: a
    built-in stand, the norm model, or a stand description file (read by the safe loader, re-derived)."""
    return _reference(key, base)[:3]


def definitions(key, base=None):
    """Each q's definition as a SymPy expression in the model's parameters (real symbols), or None for the
    norm model, whose claims state none."""
    return _reference(key, base)[3]


def _reference(key, base=None):
    """reference() and definitions() at once: (H rows, domain, names of q, definitions or None)."""
    import sympy as sp
    path = stand_file(key, base)
    if path is not None:
        from garant.derive import description
        from garant.derive.derivation import derive
        try:
            d = derive(description.load(path))
        except description.DescriptionError as e:
            raise UnknownModel(str(e)) from None
        H = d.ident.H
        params = [sp.Symbol(p.name, real=True) for p in d.model.parameters]
        defs = [sp.expand(sum((v * x for v, x in zip(d.ident.R.row(nu), params)), sp.Integer(0)))
                for nu in range(d.ident.R.rows)]
        return ([list(H.row(r)) for r in range(H.rows)],
                {"kind": "positions", "names": [a.name for a in d.model.stand.angles], **_reach(d)},
                [f"q{nu + 1}" for nu in range(H.cols)], defs)
    if kind(key) == "norm":
        # H of (2.2) entry by entry is n1^a n2^b n3^c with the exponents the generated module carries
        # (derive stops unless every entry is such a monomial; `python -m derive --check` proves the module).
        import importlib
        mod = importlib.import_module(f"garant.generated.{REGISTRY[key]['module']}")
        n = sp.symbols("n1 n2 n3", real=True)
        return ([[sp.Mul(*(x**e for x, e in zip(n, exps))) for exps in mod.H_EXPONENTS]],
                {"kind": "sphere", "names": ["n1", "n2", "n3"]}, list(mod.Q_NAMES), None)
    stand = MODELS.get(key) or (key if key in MODELS.values() else None)
    if stand is None:
        raise UnknownModel(f"unknown model {key!r} (certificates exist for {', '.join(MODELS)})")
    # A built-in model's H is the one its generated module carries (H_EXACT): `python -m derive --check`
    # (run by a test) proves that module equal to a fresh derivation, so nothing is re-derived here.
    import importlib

    from .parse import exact
    mod = importlib.import_module(f"garant.generated.{stand}")
    names = list(mod.ANGLES)
    syms = [sp.Symbol(n, real=True) for n in names]
    H = [[exact(e, syms) for e in row] for row in mod.H_EXACT]
    params = [sp.Symbol(p, real=True) for p in mod.PARAMETER_NAMES]
    return (H, {"kind": "angles", "names": names, "ranges": [["0", "2*pi"]] * len(names),
                "ranges_deg": [list(r) for r in mod.ANGLE_RANGES_DEG],
                "detents_deg": [list(d) for d in mod.ANGLE_DETENTS_DEG]},
            list(mod.Q_NAMES), [sp.expand(exact(t, params)) for t in mod.Q_DEFINITIONS])


def _reach(d):
    """The positions a stand can take: each angle's range and detents, degrees."""
    return {"ranges_deg": [list(a.range_deg) for a in d.model.stand.angles],
            "detents_deg": [list(a.detents_deg) for a in d.model.stand.angles]}
