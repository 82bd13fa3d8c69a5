import os

import pytest

from validation.peer import peer_directory


@pytest.fixture(scope="session")
def peer():
    """The Siconos peer collection shipped in validation/data (never skipped: the data is in the project)."""
    return peer_directory()


@pytest.fixture(scope="session")
def ngspice():
    """ngspice through PySpice; in CI its absence is a failure, never a silent skip."""
    import shutil
    from pathlib import Path
    found = shutil.which("ngspice") and any(Path(d).glob("libngspice.so*") for d in
                                             ("/usr/lib/x86_64-linux-gnu", "/usr/lib/aarch64-linux-gnu", "/usr/lib"))
    if not found:
        if os.environ.get("CI"):
            pytest.fail("ngspice and libngspice must be installed in CI (make test installs them)")
        pytest.skip("ngspice not installed (make test installs it)")
    return True
