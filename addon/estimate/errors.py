"""The estimate's exceptions: the caller tells them apart by type, never by
their text."""


class EstimateError(Exception):
    """The run cannot go on (unreadable clip, no ground, ...): says why, in a
    sentence for the user."""


class Cancelled(EstimateError):
    """The user asked to stop (the progress callback returned False)."""


def check_progress(progress, fraction):
    """Reports progress; raises Cancelled when the callback asks to stop."""
    if progress is not None and progress(fraction) is False:
        raise Cancelled("cancelled")
