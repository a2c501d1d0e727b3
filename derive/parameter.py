"""A named physical error parameter: the leaf every model and effect is built from."""
from dataclasses import dataclass

import sympy as sp


@dataclass(frozen=True)
class Parameter:
    """One physical error parameter: its symbol name, LaTeX, unit and meaning."""

    name: str
    latex: str
    unit: str
    meaning: str

    @property
    def symbol(self):
        return sp.Symbol(self.name, real=True)
