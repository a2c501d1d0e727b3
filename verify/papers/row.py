"""One row of `garant verify`: what was compared, with what source, and whether it held."""
from dataclasses import asdict, dataclass


@dataclass(frozen=True)
class Check:
    name: str
    source: str
    expected: str
    got: str
    passed: bool

    def as_dict(self):
        return asdict(self)
