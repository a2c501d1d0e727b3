"""Exact numbers and expressions from a certificate's text, by a whitelist grammar: nothing is evaluated.

    expr   := term (("+" | "-") term)*
    term   := unary (("*" | "/") unary)*
    unary  := ("+" | "-") unary | power
    power  := atom ("**" exponent)?
    exponent := integer | "(" ["-"] integer "/" integer ")" | "-" integer    (|value| <= MAX_EXPONENT)
    atom   := integer | name | ("sqrt" | "sin" | "cos") "(" expr ")" | "(" expr ")"

Integers have at most MAX_DIGITS digits, names are the certificate's own symbols (and pi), text is at
most MAX_CHARS long and nested at most MAX_DEPTH deep: a hostile string is refused, never run.
"""
import re

import sympy as sp

MAX_CHARS = 2_000
MAX_DIGITS = 40
MAX_DEPTH = 40
MAX_EXPONENT = 16
MAX_BITS = 4096
FUNCTIONS = {"sqrt": sp.sqrt, "sin": sp.sin, "cos": sp.cos}
#: Names the grammar reads itself (the constant and the functions): no symbol may take one.
GRAMMAR_NAMES = {"pi", *FUNCTIONS}
TOKEN = re.compile(r"\s*(?:(\d+)|([A-Za-z_][A-Za-z0-9_]*)|(\*\*|[-+*/()]))")


class ParseError(ValueError):
    """Text that is not an exact expression of the grammar above."""


def _tokens(text):
    if not isinstance(text, str):
        raise ParseError(f"expected a string, got {type(text).__name__}")
    if len(text) > MAX_CHARS:
        raise ParseError(f"an expression of {len(text)} characters (at most {MAX_CHARS})")
    out, pos = [], 0
    text = text.rstrip()
    while pos < len(text):
        m = TOKEN.match(text, pos)
        if not m:
            raise ParseError(f"unexpected {text[pos:pos + 10]!r} in {text[:60]!r}")
        number, name, op = m.groups()
        if number is not None and len(number) > MAX_DIGITS:
            raise ParseError(f"an integer of {len(number)} digits (at most {MAX_DIGITS})")
        out.append(("int", int(number)) if number is not None else ("name", name) if name else ("op", op))
        pos = m.end()
    return out


class _Parser:
    def __init__(self, text, symbols):
        self.toks, self.k, self.depth, self.text = _tokens(text), 0, 0, text
        shadow = {str(s) for s in symbols} & GRAMMAR_NAMES
        if shadow:
            raise ParseError(f"the name {sorted(shadow)[0]!r} is the grammar's own; a symbol cannot take it")
        self.names = {**{str(s): s for s in symbols}, "pi": sp.pi}

    def peek(self):
        """The next token, not consumed."""
        return self.toks[self.k] if self.k < len(self.toks) else (None, None)

    def take(self, op=None):
        """Consume the next token; it must be `want` when given."""
        tok = self.peek()
        if tok[0] is None or (op is not None and tok != ("op", op)):
            raise ParseError(f"expected {op or 'more'} in {self.text[:60]!r}")
        self.k += 1
        return tok

    def nested(self, fn):
        """Parse a sub-expression one level deeper; refuse nesting beyond the limit."""
        self.depth += 1
        if self.depth > MAX_DEPTH:
            raise ParseError(f"nested more than {MAX_DEPTH} deep")
        out = fn()
        self.depth -= 1
        return out

    def expr(self):
        """expr := term (('+' | '-') term)*, summed once (a long sum costs its length, not its square)."""
        terms = [self.term()]
        while self.peek() in (("op", "+"), ("op", "-")):
            sign = self.take()[1]
            terms.append(self.term() if sign == "+" else -self.term())
        return sp.Add(*terms) if len(terms) > 1 else terms[0]

    def term(self):
        """term := unary (('*' | '/') unary)*, multiplied once."""
        factors = [self.unary()]
        while self.peek() in (("op", "*"), ("op", "/")):
            op = self.take()[1]
            rhs = self.unary()
            if op == "/" and rhs == 0:
                raise ParseError(f"division by zero in {self.text[:60]!r}")
            factors.append(rhs if op == "*" else 1 / rhs)
        return sp.Mul(*factors) if len(factors) > 1 else factors[0]

    def unary(self):
        """unary := '-' unary | power."""
        if self.peek() in (("op", "+"), ("op", "-")):
            sign = self.take()[1]
            inner = self.nested(self.unary)
            return inner if sign == "+" else -inner
        return self.power()

    def power(self):
        """power := atom ('**' exponent)?."""
        base = self.atom()
        if self.peek() == ("op", "**"):
            self.take()
            e = self.exponent()
            if base.is_Rational and max(abs(base.p), base.q).bit_length() * abs(e) > MAX_BITS:
                raise ParseError(f"a number of more than {MAX_BITS} bits in {self.text[:60]!r}")
            value = base ** e
            if value.is_Pow and value.exp.is_number and abs(value.exp) > MAX_EXPONENT:
                raise ParseError(f"a power beyond {MAX_EXPONENT} in {self.text[:60]!r}")
            return value
        return base

    def exponent(self):
        """exponent := a small integer or a half-integer (a root), signed."""
        kind, value = self.peek()
        if (kind, value) == ("op", "("):
            self.take()
            neg = self.peek() == ("op", "-") and self.take()
            p = self.take()
            self.take("/")
            q = self.take()
            self.take(")")
            if p[0] != "int" or q[0] != "int" or q[1] == 0:
                raise ParseError(f"an exponent must be an integer or a fraction of integers in {self.text[:60]!r}")
            e = sp.Rational(-p[1] if neg else p[1], q[1])
        else:
            neg = self.peek() == ("op", "-") and self.take()
            tok = self.take()
            if tok[0] != "int":
                raise ParseError(f"an exponent must be an integer in {self.text[:60]!r}")
            e = sp.Integer(-tok[1] if neg else tok[1])
        if abs(e) > MAX_EXPONENT:
            raise ParseError(f"exponent {e} is beyond {MAX_EXPONENT}")
        return e

    def atom(self):
        """atom := integer | allowed name | sqrt(expr) | sin(expr) | cos(expr) | (expr)."""
        kind, value = self.take()
        if kind == "int":
            return sp.Integer(value)
        if kind == "name" and value in FUNCTIONS:
            self.take("(")
            arg = self.nested(self.expr)
            self.take(")")
            if value == "sqrt" and arg.is_number and arg.is_negative:
                raise ParseError(f"the square root of a negative number in {self.text[:60]!r}: not a real number")
            return FUNCTIONS[value](arg)
        if kind == "name":
            if value not in self.names:
                raise ParseError(f"unknown name {value!r} (allowed: {', '.join(sorted(self.names))}, "
                                 f"{', '.join(FUNCTIONS)})")
            return self.names[value]
        if value == "(":
            inner = self.nested(self.expr)
            self.take(")")
            return inner
        raise ParseError(f"unexpected {value!r} in {self.text[:60]!r}")


def exact(text, symbols=()):
    """The SymPy expression the text denotes, from the grammar above; ParseError otherwise."""
    p = _Parser(text, symbols)
    if not p.toks:
        raise ParseError("an empty expression")
    value = p.expr()
    if p.k != len(p.toks):
        raise ParseError(f"unexpected {p.toks[p.k][1]!r} in {text[:60]!r}")
    if value.is_number and value.is_real is False:
        raise ParseError(f"{text[:60]!r} is not a real number")
    _in_field(value, text)
    return value


#: The radicands a certificate's numbers may hold: garant certifies in Q(sqrt2, sqrt3) (multiples of 15
#: degrees), where exact comparisons are quick; any other root (nested, cubic, of a large prime) is refused
#: before a comparison could take unbounded time.
RADICANDS = (2, 3, 6)


def _in_field(value, text):
    """ParseError unless every root in `value` is sqrt(2), sqrt(3) or sqrt(6) and every sine or cosine has
    an angle symbol in its argument (a sine of a number SymPy cannot write in radicals is refused)."""
    for p in value.atoms(sp.Pow):
        if not p.exp.is_Integer and not (abs(p.exp) == sp.Rational(1, 2) and p.base in RADICANDS):
            raise ParseError(f"{text[:60]!r}: the root {str(p)[:40]} is not sqrt(2), sqrt(3) or sqrt(6) (certificates "
                             "hold numbers of Q(sqrt2, sqrt3))")
    for f in value.atoms(sp.sin, sp.cos):
        if f.args[0].is_number:
            raise ParseError(f"{text[:60]!r}: {str(f)[:40]} is not a number of Q(sqrt2, sqrt3)")
