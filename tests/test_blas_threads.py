"""One BLAS thread per process unless the user's environment sets one: the circuits' matrices are small and a
multithreaded BLAS made a 5 x 5 matrix exponential 12 times slower on two busy cores (converters/__init__.py)."""
import json
import os
import subprocess
import sys

PROBE = ("import converters, numpy, scipy.linalg, json; from threadpoolctl import threadpool_info; "
         "print(json.dumps(sorted({i['num_threads'] for i in threadpool_info() if i['user_api'] == 'blas'})))")


def _threads(env: dict) -> list:
    clean = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS",
                                                              "MKL_NUM_THREADS")}
    done = subprocess.run([sys.executable, "-c", PROBE], env={**clean, **env}, capture_output=True, text=True,
                          check=True, timeout=120)
    return json.loads(done.stdout)


def test_every_blas_has_one_thread_after_the_package_is_imported():
    assert _threads({}) == [1]


def test_a_users_blas_setting_is_kept():
    assert _threads({"OPENBLAS_NUM_THREADS": "2"}) == [2]
