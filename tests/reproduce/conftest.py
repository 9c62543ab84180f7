"""The reproductions' simulations run once a session.

Several tests read the same reproduction: ``test_honest_flags`` builds each table three
times with different paper values, the CLI test and the table tests once more. The
numbers do not depend on the paper values (the honest-flags test checks that), so the
seeded simulations behind a table (``simulations()`` of selfcal and ebner) are kept per
session, keyed by their arguments and the module constants that size them; the rows,
flags and the paper comparison are built anew by every call.
"""

from __future__ import annotations

import copy

import pytest

from orientviz.reproduce import ebner, selfcal

#: module constants read by each cached function (their values are part of the key)
SIZES = {selfcal: ("CASES", "ERROR_TYPES"), ebner: ("STRIPS", "SPACINGS", "STRIPS_4")}


def _once(module, func):
    store: dict = {}

    def cached(*args, **kwargs):
        key = (args, tuple(sorted(kwargs.items())),
               tuple(repr(getattr(module, n)) for n in SIZES[module]))  # fmt: skip
        if key not in store:
            store[key] = func(*args, **kwargs)
        return copy.deepcopy(store[key])

    return cached


@pytest.fixture(scope="session", autouse=True)
def simulations_once():
    with pytest.MonkeyPatch.context() as mp:
        for module in SIZES:
            mp.setattr(module, "simulations", _once(module, module.simulations))
        yield
