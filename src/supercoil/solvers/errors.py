"""The numerical failures of the sparse factorisations, raised to the caller."""


class SingularMatrixError(RuntimeError):
    """The KKT matrix is (numerically) singular."""


class InertiaError(RuntimeError):
    """The inertia could not be certified."""
