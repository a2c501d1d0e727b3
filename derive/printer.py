"""Code printer for generated modules: SymPy's NumPyPrinter with numpy imported as `np`."""
import sympy as sp
from sympy.printing.numpy import NumPyPrinter


class GarantPrinter(NumPyPrinter):
    """NumPy printer that writes `np.cos` instead of `numpy.cos` and exact rationals as p/q."""

    def _module_format(self, fqn, register=True):
        name = super()._module_format(fqn, register)
        return "np." + name[len("numpy."):] if name.startswith("numpy.") else name

    def _print_Rational(self, expr):
        return f"{expr.p}/{expr.q}"

    def _print_Integer(self, expr):
        """Beyond 2^53 (an exactly normalised tilted axis) as a float literal: numpy functions take no
        Python integers of that size, and the generated module computes in floats anyway."""
        return repr(float(expr.p)) if abs(expr.p) > 2**53 else str(expr.p)

    def _print_Half(self, expr):
        return self._print_Rational(expr)


def pycode(expr):
    """Python/numpy source of one scalar expression."""
    return GarantPrinter({"fully_qualified_modules": True}).doprint(sp.sympify(expr))


def linear_text(coeffs, names):
    """'Gamma11 - Delta_g' from coefficients over names, leading term first, zeros left out."""
    out = ""
    for c, n in zip(coeffs, names):
        if c == 0:
            continue
        size = abs(c)
        mag = "" if size == 1 else f"({size})*" if isinstance(size, sp.Add) else f"{size}*"
        sign = "-" if c < 0 else "+"
        out += (f"{'-' if c < 0 else ''}{mag}{n}" if not out else f" {sign} {mag}{n}")
    return out or "0"
