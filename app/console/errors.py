"""The console's own error."""


class ConsoleError(ValueError):
    """A command that cannot be carried out now; the message says why."""
