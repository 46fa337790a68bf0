"""``did you mean``: the nearest of the valid names to a misspelt one, for the one-line errors that list them."""

import difflib


def nearest(name, choices, cutoff=0.6):
    """The choice most like ``name``, case aside (difflib's ratio of at least ``cutoff``), or None."""
    lower = {}
    for choice in choices:
        lower.setdefault(str(choice).lower(), str(choice))
    found = difflib.get_close_matches(str(name).lower(), list(lower), n=1, cutoff=cutoff)
    return lower[found[0]] if found else None


def did_you_mean(name, choices):
    """``"; did you mean 'lqr'?"`` for the nearest of ``choices`` to ``name``, or ``""`` where none is near."""
    found = nearest(name, choices)
    return "" if found is None or found == name else f"; did you mean {found!r}?"
