"""A named physical error parameter: the leaf every model and effect is built from."""
from dataclasses import dataclass

import sympy as sp


@dataclass(frozen=True)
class Parameter:
    """One physical error parameter: its symbol name, LaTeX, unit, meaning and, where the description
    states one, its a-priori bound (|value| <= bound, in its unit): the premise of a guaranteed bound."""

    name: str
    latex: str
    unit: str
    meaning: str
    bound: float | None = None

    @property
    def symbol(self):
        """The parameter's real SymPy symbol."""
        return sp.Symbol(self.name, real=True)
