"""The one exact linear solver of garant: Gauss-Jordan elimination over any field.

Used with Fractions (the rational estimators of (7)-(8) of 000, certificates, section 6) and with the
elements of Q(sqrt2, sqrt3) (verify/solve/field.py): exact arithmetic has no rounding to pivot against,
so the first nonzero pivot is as good as any.
"""
from fractions import Fraction


def solve_exact(columns, target, convert=Fraction):
    """Exact x with sum_k x_k columns[k] = target, or None when the columns are dependent or miss the
    target. `convert` maps each entry into the field (Fraction by default); the field's elements need
    +, -, *, / and truth (nonzero)."""
    m, k = len(target), len(columns)
    rows = [[convert(columns[j][i]) for j in range(k)] + [convert(target[i])] for i in range(m)]
    r = 0
    for c in range(k):
        p = next((i for i in range(r, m) if rows[i][c]), None)
        if p is None:
            return None
        rows[r], rows[p] = rows[p], rows[r]
        pivot = rows[r][c]
        rows[r] = [v / pivot for v in rows[r]]
        for i in range(m):
            if i != r and rows[i][c]:
                f = rows[i][c]
                rows[i] = [a - f * b for a, b in zip(rows[i], rows[r])]
        r += 1
    if any(rows[i][k] for i in range(r, m)):
        return None
    return [rows[i][k] for i in range(k)]
