"""One row of `garant verify`: what was compared, with what source, and whether it held."""
from dataclasses import asdict, dataclass


@dataclass(frozen=True)
class Check:
    """One row of `garant verify`: the check, its source (paper and equation), expected, got, passed."""

    name: str
    source: str
    expected: str
    got: str
    passed: bool

    def as_dict(self):
        """The row as a dictionary (the --json output)."""
        return asdict(self)
