"""The two kinds of failure the command line turns into one line on stderr and exit status 2."""


class DataError(ValueError):
    """A problem with the user's input: the CLI prints it as one line and exits with status 2."""


class LPFailed(RuntimeError):
    """The solver did not reach an optimum (infeasible plan or numerical failure)."""
