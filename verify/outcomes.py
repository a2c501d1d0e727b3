"""What a job's outcome is, declared once: the status of a result (a word) and the command's exit status.

The ground floor beside errors.py: results, batches and the command line take their words and numbers from
here, and the README's sentence on exit statuses is `exit_sentence()` (a test compares them), as cvxpy keeps its
solver statuses and scipy its HiGHS status map in one place.
"""
import enum


class Status(str, enum.Enum):
    """What came out of a job, in a word (`Result.status`; a batch row's `status`). A str: it compares equal to
    its word and prints as it."""

    DONE = "done"                                    # the job ran
    CONSISTENT = "consistent"                        # the readings fit the noise bound within the premises
    REFUTED = "refuted"                              # the readings refute the noise bound (or a premise)
    PREMISE_REFUTED = "premise refuted"              # q beyond what its parameters' stated bounds allow
    EXPLAINED = "explained"                          # diagnose: the effects named close the gap
    UNEXPLAINED = "unexplained"                      # diagnose: no catalogue effect closes it
    MEASURE = "measure"                              # next: measure the position it names
    ERROR = "error"                                  # a batch's log that could not be calibrated

    def __str__(self):
        return self.value


class Verdict(str, enum.Enum):
    """A unit's verdict against its specification in a batch (a row's `verdict`), in the order the summary counts
    them: every guaranteed interval within its limit, one wholly outside, neither, or retest (the recording proves
    nothing of the unit: not calibrated, or refuting its noise bound)."""

    PASS = "pass"
    FAIL = "fail"
    UNDECIDED = "undecided"
    RETEST = "retest"

    def __str__(self):
        return self.value


class Exit(enum.IntEnum):
    """The command's exit status. Each member's `meaning` is what the README says of it."""

    OK = 0
    FAILED = 1
    BAD_INPUT = 2
    REFUTED = 3
    SPEC_FAILED = 4
    RETEST = 5
    INTERRUPTED = 130

    @property
    def meaning(self) -> str:
        """What this exit status says, in the words of the README's sentence."""
        return _MEANINGS[self]


_MEANINGS = {
    Exit.OK: "done",
    Exit.FAILED: "a check or certificate failed (or garant itself failed, said in one line)",
    Exit.BAD_INPUT: "bad input (one line on standard error, nothing written; a batch of apply: some log, its count "
                    "printed)",
    Exit.REFUTED: "the data refute the stated noise bound or an a-priori bound (no bound is given then)",
    Exit.SPEC_FAILED: "a batch: some unit failed its spec",
    Exit.RETEST: "a batch: some log proves nothing of its unit (retest)",
    Exit.INTERRUPTED: "interrupted (Ctrl-C; nothing half written)",
}


def exit_sentence() -> str:
    """The README's sentence on exit statuses, made from Exit (one line; the README wraps it)."""
    return "Exit status: " + "; ".join(f"{int(e)} {e.meaning}" for e in Exit) + "."
