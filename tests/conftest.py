import os

import pytest

from validation.peer import peer_directory


@pytest.fixture(scope="session")
def peer():
    """The Siconos peer collection; it must be present in CI, elsewhere its tests skip with a reason."""
    path = peer_directory()
    if path is None:
        if os.environ.get("CI"):
            pytest.fail("the Siconos peer collection must be present in CI (../shared/peer/siconos-lcp "
                        "or $PCSUITE_PEER_DIR)")
        pytest.skip("Siconos peer collection not found (set PCSUITE_PEER_DIR)")
    return path
