"""The project's one expected-error type, mapped by the CLI to a clean message and exit code."""
from __future__ import annotations

__all__ = ["SeamlessUsdError", "InputError", "UndecodableImage", "UsageError", "Interrupted"]


class SeamlessUsdError(Exception):
    """An expected failure with a one-line message for the user.

    The message names the prim as ``<path>`` or the asset as ``@path@`` and says what to do.
    """


class InputError(SeamlessUsdError):
    """A stage, document or image that cannot be read (CLI exit code 2)."""


class UndecodableImage(InputError):
    """An image whose header reads but whose pixels do not decode: truncated or corrupt (``path``: the file)."""

    def __init__(self, message: str, path):
        super().__init__(message)
        self.path = path


class UsageError(SeamlessUsdError):
    """Options that contradict each other or name something unknown (CLI exit code 2)."""


class Interrupted(KeyboardInterrupt):
    """A run stopped by Ctrl-C (or SIGTERM) carrying what it had done (``report``): a run's report (the tiles written
    so far are on disk and in the cache; each stack's row says how far it got), or a scan's result (what it had
    scanned). Caught as any KeyboardInterrupt."""

    def __init__(self, report):
        super().__init__("interrupted")
        self.report = report
