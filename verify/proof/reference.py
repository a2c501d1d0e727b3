"""What a certificate of a built-in model must carry, re-derived from derive/: its H rows and domain.

Both the builder and the checker take H from here, so a certificate is checked against the model it
names, never against the H it brings along.
"""
#: Certificate model keys and the models they name.
MODELS = {"two-axis": "two_axis", "single-axis": "single_axis", "three-axis": "three_axis", "norm": None}


class UnknownModel(ValueError):
    """A certificate names a model garant does not know."""


def reference(key):
    """(H rows as SymPy expressions, domain dict, names of q) of the model a certificate names."""
    if key == "norm":
        from garant.derive import norm
        from garant.generated import norm as mod
        return ([list(norm.H(norm.NormModel(mod.AXES)))], {"kind": "sphere", "names": ["n1", "n2", "n3"]},
                list(mod.Q_NAMES))
    stand = MODELS.get(key) or (key if key in MODELS.values() else None)
    if stand is None:
        raise UnknownModel(f"unknown model {key!r} (certificates exist for {', '.join(MODELS)})")
    from garant.derive.builtin import MODELS as BUILTIN
    from garant.derive.derivation import derive
    d = derive(BUILTIN[stand])
    names = [a.name for a in d.model.stand.angles]
    H = d.ident.H
    return ([list(H.row(r)) for r in range(H.rows)],
            {"kind": "angles", "names": names, "ranges": [["0", "2*pi"]] * len(names)},
            [f"q{nu + 1}" for nu in range(H.cols)])
