import os

import numpy as np
import pytest
from hypothesis import settings
from threadpoolctl import threadpool_limits
from typer.testing import CliRunner

# One BLAS thread for the whole test run, as the CLI uses
# (supercoil.cli.main, unless the environment sets the count): results then do not depend on the
# machine's core count (a penalty solve landed on another state with two threads
# than with one) and the many small dense solves run faster on a loaded machine.
# (numpy is already loaded by pytest's plugins here, so the environment variable
# would come too late; threadpoolctl limits the loaded library.)
_ONE_BLAS_THREAD = threadpool_limits(limits=1, user_api="blas")

# CI runs the same hypothesis examples every time (a landing must not depend
# on which random examples a run happens to draw); local runs keep exploring.
settings.register_profile("ci", derandomize=True, print_blob=True)
if os.environ.get("CI"):
    settings.load_profile("ci")


def smooth_closed_curve(n_nodes: int, length: float = 1.0, wobble: float = 0.3) -> np.ndarray:
    """A smooth non-planar closed curve sampled at n_nodes points, scaled to perimeter ~length."""
    s = 2 * np.pi * np.arange(n_nodes) / n_nodes
    pts = np.stack([np.cos(s) + wobble * np.cos(2 * s),
                    np.sin(s) + 0.5 * wobble * np.sin(3 * s),
                    wobble * np.sin(2 * s)], axis=1)
    perimeter = np.sum(np.linalg.norm(np.roll(pts, -1, 0) - pts, axis=1))
    return pts * (length / perimeter)


@pytest.fixture
def rng():
    return np.random.default_rng(20261122)


def split_into_halves(A):
    """``A`` (sparse) as a CSR matrix that stores every entry twice, each half of it: not
    in canonical format, so code that sums duplicates (scipy's ``bmat``) and code that
    reads the raw arrays can be compared on it."""
    import scipy.sparse as sp

    coo = A.tocoo()
    n = A.shape[0]
    rows = np.concatenate([coo.row, coo.row])
    by_row = np.argsort(rows, kind="stable")
    indptr = np.concatenate([[0], np.cumsum(np.bincount(rows, minlength=n))])
    out = sp.csr_matrix((np.concatenate([coo.data, coo.data])[by_row] / 2,
                         np.concatenate([coo.col, coo.col])[by_row], indptr), shape=A.shape)
    assert not out.has_canonical_format
    return out



def with_rank_one_terms(rng, H: np.ndarray, J: np.ndarray, rank_one: int):
    """``(HessianParts(H) plus rank_one random dense symmetric rank-one terms of either
    sign, csr J)``: the KKT test problems of the solver tests."""
    import scipy.sparse as sp

    from supercoil.solvers.problem import HessianParts

    n = H.shape[0]
    vecs = rng.standard_normal((rank_one, n))
    coefs = rng.uniform(0.5, 3.0, rank_one) * rng.choice([-1, 1], rank_one)
    return HessianParts(sp.csr_matrix(H), vecs, coefs), sp.csr_matrix(J)


@pytest.fixture
def runner() -> CliRunner:
    """Invokes the ``supercoil`` app in-process (typer's test runner)."""
    return CliRunner()


def same_bits(mine, ref) -> bool:
    """Whether two CSR matrices are the same to the bit: shape, index dtypes, indptr,
    indices and the bits of every value."""
    return (mine.shape == ref.shape and mine.indices.dtype == ref.indices.dtype
            and mine.indptr.dtype == ref.indptr.dtype
            and np.array_equal(mine.indptr, ref.indptr)
            and np.array_equal(mine.indices, ref.indices)
            and np.array_equal(mine.data.view(np.int64), ref.data.view(np.int64)))
