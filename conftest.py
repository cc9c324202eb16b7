"""Settings for every test directory (tests/, hil_tests/).

In CI (``CI`` set, as `.ci/run` is run) hypothesis is derandomised: each run explores the
same examples, so a CI result can be reproduced exactly. A developer's ``make test`` keeps
exploring new examples on every run, which is where new counterexamples are found.
"""

import os

from hypothesis import settings

settings.register_profile("ci", derandomize=True)
if os.environ.get("CI"):
    settings.load_profile("ci")
