"""The two kinds of failure the command line turns into one line on stderr and exit status 2."""

#: Marks an option's name inside an error's text (`opt`), so each caller names it its own way.
_MARK = "\x1f"
#: The command's spelling of the API arguments whose option is named otherwise.
FLAGS = {"which_run": "--run", "k": "--still-factor", "effects": "--effect"}


def opt(name):
    """An option inside an error's text, by its API name: the command prints `--name`, the API `name=`."""
    return f"{_MARK}{name}{_MARK}"


class DataError(ValueError):
    """A problem with the user's input: the CLI prints it as one line and exits with status 2. `param`:
    the option it is about (the first `opt` in the text when not given)."""

    def __init__(self, message, param=None):
        self.raw = str(message)
        named = self.raw.split(_MARK)[1::2]
        self.param = param or (named[0] if named else None)
        super().__init__(self.render("command"))

    def render(self, style="command"):
        """The text with each option named as the command (`--imu`) or the API (`imu=`) spells it."""
        parts = self.raw.split(_MARK)
        for i in range(1, len(parts), 2):
            parts[i] = (FLAGS.get(parts[i], "--" + parts[i].replace("_", "-")) if style == "command"
                        else f"{parts[i]}=")
        return "".join(parts)


class NotExact(ValueError):
    """H is not exact where an exact computation needs it (a detent off 15 degrees, an axis outside Q(sqrt2,
    sqrt3)): the caller falls back to floating point, or says so in one line."""


class LPFailed(RuntimeError):
    """The solver did not reach an optimum (infeasible plan or numerical failure). `status`: the solver's own
    word for it (HiGHS's model status, lower case: "infeasible", "unbounded", "time limit reached", ...)."""

    def __init__(self, message, status=""):
        super().__init__(message)
        self.status = str(status).lower()
