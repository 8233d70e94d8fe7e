"""Hard-contact second-order check of the stable stretches of Coleman & Swigon's β_II.

Run from the repository root:

    python benchmarks/bench_hard_contact_check.py [--nodes 132] [--branches /tmp/hc]
        [--stable 5 --unstable 2 | --all]

The continuation (``bench_beta_secondary.py``) finds stretches of the secondary
branch β_II with unstable count 0 where Coleman & Swigon 2002 (ring diagrams with
self-contact) find only β between B₁ and P stable. Its contact is the barrier (a
smooth potential acting on gaps below 1 % of D, ``ContactOptions.barrier_activation``,
integrated over the cubic B-spline); theirs is a hard constraint. This script decides whether the
barrier makes the difference: at states of β (between B₁ and P, the positive
control, and beyond P) and of both halves of β_II (on their count-0 stretches and
on neighbouring unstable ones) it solves the same ring at the same ΔLk with hard
contact and counts the unstable directions there.

Hard contact: the ``exact`` treatment of :class:`~supercoil.contact.problem.ContactProblem`
on the same cubic B-spline (it takes the ``pairs`` formulation: one constraint
``g = d - D = 0`` per active piece pair, ``d`` the pieces' closest distance). The
active set starts as the piece pairs within 1 % of D of the barrier state whose
closest points are local minima of the curve distance (the barrier's contacts,
shadows dropped), kept linearly independent
(:func:`~supercoil.contact.solve.independent_pairs`), and the active-set loop of
:func:`~supercoil.contact.solve.solve_contact` runs from there (Newton in
stationary mode: an unstable state must not be minimised away; see
:func:`hard_contact` for the retries, and for the polygon's exact contact, tried
where the spline's is not solved).

Count: :func:`~supercoil.stability.analysis.analyse` on the exact problem (the
Hessian of the Lagrangian, contact multipliers included, on the null space of the
rod's constraints and of the active contacts; rigid motions pinned, the material
sliding gauged out). With every contact multiplier strictly positive that null
space is the critical cone, so this is the second-order condition of the hard
problem. Oracle: a dense eigen-decomposition of ``Z^T H_L Z`` against ``Z^T M Z``,
``Z`` a null-space basis of the active Jacobian and of the M-weighted rigid
motions and sliding on all DOFs (no pins), counted below -1e-6 as ``analyse``
counts; the barrier's count is the continuation's stored one, ``analyse``'s and
the same oracle's. Contacts with a multiplier below 1e-3 of the largest are
reported as weakly active (there the critical cone is not a subspace), and active
pairs whose closest point is a piece end as "at a junction" (see
:func:`hard_contact_row`).

Checks per state: the KKT residual without any gauge, no penetration, the contact
positions (s1, s2) matched to the barrier's (the largest distance, in segment
lengths h, from a hard contact to the nearest barrier contact and the reverse),
the distance moved from the barrier state, Lk = Tw + Wr (twist from the material
frames, writhe from the double sum). Prints one table row per state (``--all``:
every point of the three branches, 86 s at N = 132, 207 s at N = 204); the
branches are computed as ``bench_beta_secondary.py`` computes them (20 to 40 s)
and saved to ``--branches`` (read from there when present).
``benchmarks/results/beta_stability.md`` records the results at N = 132 and 204.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from scipy.linalg import eigh, null_space

TWIST_RATIO, LENGTH_OVER_DIAMETER = 2 / 3, 122.0
WEAK_MULTIPLIER = 1e-3  # of the largest contact force: "weakly active"
ZERO_TOLERANCE = 1e-6  # analyse's default: eigenvalues within it are zero modes


def branches(nodes: int, folder: Path, max_points: int = 90):
    """β with contact and both halves of β_II from P, as bench_beta_secondary.py computes
    them; saved under ``folder`` and read from there when present."""
    from supercoil.io.store import load, save

    names = ("beta_contact", "beta_II+", "beta_II-")
    path = folder / f"branches_{nodes}.h5"
    if path.exists():
        stored = load(path)
        return {name: stored.branch(name) for name in names}
    from supercoil.problems.ring_diagram import DiagramOptions, ring_diagram
    from supercoil.problems.ring_diagram.secondary import follow_bifurcating_branch

    folder.mkdir(parents=True, exist_ok=True)
    options = DiagramOptions(TWIST_RATIO, LENGTH_OVER_DIAMETER, n_nodes=nodes, modes=(3,),
                             max_excess_link=6.0, contact_max_points=200)
    start = time.perf_counter()
    diagram = ring_diagram(options)
    beta = diagram.branch("beta_contact")
    out = {"beta_contact": beta}
    p = beta.points_of_kind("bifurcation")[-1]  # P
    for side in (1, -1):
        name = f"beta_II{'+' if side > 0 else '-'}"
        out[name] = follow_bifurcating_branch(diagram, beta, p, side, max_points=max_points,
                                              name=name)
    save(path, list(out.values()))
    print(f"branches computed in {time.perf_counter() - start:.1f} s, saved to {folder}")
    return out


def chosen_points(branch, stable: int, unstable: int) -> list[int]:
    """Indices of ``stable`` points with count 0 and ``unstable`` with count >= 1, evenly
    spread over each set, two points away from special points (near a bifurcation or
    fold an eigenvalue is near zero, and a shift of the point decides its sign)."""
    near = np.zeros(len(branch), dtype=bool)
    for p in branch.special_points:
        if p.kind in ("fold", "bifurcation"):
            near[max(p.index - 1, 0):p.index + 3] = True
    near[:2] = True  # the switch's first points sit on the parent's bifurcation
    picks = []
    for wanted, mask in ((stable, branch.unstable_count == 0),
                         (unstable, branch.unstable_count >= 1)):
        candidates = np.flatnonzero(mask & ~near)
        if wanted and len(candidates):
            picks += candidates[np.linspace(0, len(candidates) - 1, wanted).round()
                                .astype(int)].tolist()
    return sorted(set(picks))


def onset_window(branch) -> list[int]:
    """Indices of ``branch`` (β with contact) from its contact onset to its first
    bifurcation point (B₁): the barrier's reach smooths the onset of contact there."""
    onset = branch.points_of_kind("contact_onset")
    first = branch.points_of_kind("bifurcation")
    if not onset or not first:
        return []
    return list(range(onset[0].index, first[0].index + 2))


def contacts(problem, q, multipliers) -> tuple[np.ndarray, str]:
    """``((k, 2) positions (s1, s2) / L of the touching pairs carrying at least 1 % of the
    largest force, "points + intervals")`` of :func:`~supercoil.contact.report.contact_summary`
    (the grouping's floor: a barrier pair at the edge of its reach carries a vanishing
    force)."""
    from supercoil.contact.report import GROUPING_FLOOR, contact_summary

    summary = contact_summary(problem, q, multipliers)
    pairs = summary["contacts"]
    largest = max((c["force"] for c in pairs), default=0.0)
    positions = np.array([(c["s1"], c["s2"]) for c in pairs
                          if c["force"] >= GROUPING_FLOOR * largest]).reshape(-1, 2)
    label = f"{summary['n_contact_points']}"
    if summary["n_contact_intervals"]:
        label += f" + {summary['n_contact_intervals']} line"
    return positions, label


def _farthest(a: np.ndarray, b: np.ndarray) -> float:
    """Largest distance (max norm, periodic in s / L) from a point of ``a`` to ``b``."""
    if not len(a) or not len(b):
        return float("nan")
    gap = np.abs(a[:, None] - b[None])
    gap = np.minimum(gap, 1.0 - gap)
    return float(np.max(np.min(np.max(gap, axis=2), axis=1)))


def initial_active_set(hard, q: np.ndarray, reach: float = 0.01) -> np.ndarray:
    """Piece pairs within ``(1 + reach) D`` at ``q`` (default: the barrier's reach, so that
    a state the barrier does not touch starts without contact) whose closest points are
    local minima of the curve distance, closest first, with independent gap gradients."""
    from supercoil.contact.solve import independent_pairs
    from supercoil.contact.spline_distance import local_minimum_pairs

    st = hard.pair_state(q, hard.diameter * (1.0 + reach))
    keep = local_minimum_pairs(q.reshape(-1, 3), hard.curve.pieces, st.pairs, st.s, st.t)
    active, _ = independent_pairs(hard, q, st.pairs[keep], -st.distance[keep])
    return active


def dense_reduced_eigenvalues(problem, q: np.ndarray, multipliers: np.ndarray) -> np.ndarray:
    """Oracle: all eigenvalues of ``Z^T H_L Z y = mu Z^T M Z y``, ``Z`` a null-space basis of
    the constraint Jacobian (rod and active contacts) and of ``S^T M``, ``S`` the six
    rigid motions and the material sliding, on all DOFs (no pins)."""
    from supercoil.solvers.newton import lagrangian_hessian

    n = problem.n_dofs
    H = lagrangian_hessian(problem, q, multipliers).restrict(np.arange(n)).dense()
    S = np.vstack([problem.symmetry_modes(q), problem.near_symmetry_modes(q)])
    mass = problem.mass
    Z = null_space(np.vstack([problem.constraint_jacobian(q).toarray(), S * mass]))
    A = Z.T @ H @ Z
    B = Z.T @ (mass[:, None] * Z)
    return eigh(0.5 * (A + A.T), 0.5 * (B + B.T), eigvals_only=True)


def hard_contact(base, q: np.ndarray, diameter: float, curve: str, attempts: int = 4,
                 minimise: bool = False):
    """``(problem, result, mode)``: the exact-treatment equilibrium on ``curve`` from ``q``
    (``problem`` None when not solved; ``result`` the last attempt's).

    Spline: the active-set loop of :func:`~supercoil.contact.solve.solve_contact` (its
    ``_active_set_loop``, without the augmented-Lagrangian fallback) from
    :func:`initial_active_set`, Newton in stationary mode (an unstable state must not be
    minimised away). A piece pair's distance is
    only piecewise smooth: when a contact's closest points move across a junction of
    pieces the active pair's minimiser sticks to its side of the square and Newton
    stalls (measured: the residual stops at 2.1 on β_II+ at ΔLk 5.58). The set is
    then picked again at the stalled state (up to ``attempts`` times in all).
    Polygon (the chords sag inside the spline by up to ``h^2 kappa / 8``, a few per cent
    of D here, so ``q`` is not next to its solution): the whole exact solve
    (augmented-Lagrangian start, then the active-set loop), stationary first, then,
    if ``minimise`` (asked only where the barrier's count is 0: a minimisation leaves a
    saddle), minimising; the mode that converged is returned with the result.
    """
    from supercoil.contact.options import ContactOptions
    from supercoil.contact.problem import ContactProblem
    from supercoil.contact.solve import _active_set_loop, solve_contact
    from supercoil.solvers.newton import NewtonOptions

    stationary = NewtonOptions(mode="stationary", tolerance=1e-10, max_iterations=200)

    def solved(problem, res):
        return (res.converged and res.admissible
                and len(res.multipliers) == problem.n_constraints)

    options = ContactOptions(diameter, treatment="exact", curve=curve, formulation="pairs")
    res = None
    if curve == "spline":
        start = q
        for _ in range(attempts):
            hard = ContactProblem(base, options)
            res = _active_set_loop(hard, start, initial_active_set(hard, start), None,
                                   stationary, 0, 0, max_cycles=30)
            if solved(hard, res):
                return hard, res, "stationary"
            stalled = getattr(res, "q", None)
            if stalled is None or not np.all(np.isfinite(stalled)):
                break
            start = stalled
        return None, res, None
    for mode in ("stationary", "minimize") if minimise else ("stationary",):
        hard = ContactProblem(base, options)
        res = solve_contact(hard, q, NewtonOptions(mode=mode, tolerance=1e-10,
                                                   max_iterations=200))
        if solved(hard, res):
            return hard, res, mode
    return None, res, None


def hard_contact_row(base, hard, res, q, barrier_positions: np.ndarray,
                     excess_link: float) -> dict:
    """Count, oracle and checks of a hard-contact equilibrium (module docstring)."""
    from supercoil.problems.ring_branches import ring_records
    from supercoil.problems.ring_diagram.records import kkt_residual
    from supercoil.stability.analysis import analyse

    forces = -res.multipliers[hard.n_equalities:]
    # an active pair whose closest point is a piece end (a junction of the spline): its
    # distance is the minimum over its own pieces only, whose Hessian there exceeds the
    # curve distance's (the neighbouring piece is not minimised over), and the force
    # times it counts as extra negative curvature: such a count is not the curve's
    _d, s, t = hard.pair_distances(res.q, hard.active)
    ends = np.minimum(np.minimum(s, 1.0 - s), np.minimum(t, 1.0 - t))
    report = analyse(hard, res.q, res.multipliers)
    dense = dense_reduced_eigenvalues(hard, res.q, res.multipliers)
    after, label = contacts(hard, res.q, res.multipliers)
    return {"count": report.unstable_count, "certified": report.certified, "dense": int(np.sum(dense < -ZERO_TOLERANCE)),
            "zero_modes": report.zero_modes, "lowest": float(dense[0]),
            "contacts": label, "junctions": int(np.sum(ends < 1e-6)),
            "min_force": float(forces.min()) if forces.size else float("nan"),
            "weak": int(np.sum(forces < WEAK_MULTIPLIER * forces.max())) if forces.size else 0,
            "kkt": kkt_residual(hard, res.q, res.multipliers),
            "penetration": res.max_penetration_over_diameter,
            # the same contact set: every hard contact lies at a barrier contact and the
            # reverse (each a touching pair; a point contact spans one or two of them)
            "shift_to_barrier": _farthest(after, barrier_positions),
            "shift_from_barrier": _farthest(barrier_positions, after),
            "link_error": float(ring_records(base)(res.q, res.multipliers,
                                                   excess_link)["link_error"]),
            "moved_over_D": float(np.max(np.abs(res.q - q))) / hard.diameter}


def check_state(branch, i: int, nodes: int,
                length_over_diameter: float = LENGTH_OVER_DIAMETER) -> dict:
    """The barrier and hard-contact counts and the checks of point ``i`` of ``branch`` (a
    ring of ``nodes`` nodes, C/A = 2/3; module docstring). The polygon's hard contact is
    tried only where the spline's is not solved (a line contact)."""
    from supercoil.contact.options import ContactOptions
    from supercoil.contact.problem import ContactProblem
    from supercoil.problems.ring_branches import twisted_circle_problem
    from supercoil.stability.analysis import analyse

    q = np.asarray(branch.states[i], dtype=float)
    lam = np.asarray(branch.multipliers[i], dtype=float)
    excess_link = float(branch.parameter_values[i])
    base, _ = twisted_circle_problem(TWIST_RATIO, excess_link, nodes)
    base.accept(q)  # a jump: the reference frames are rebuilt, Lk_u from the double sum
    base.repin(q)
    D = base.rod.length / length_over_diameter
    barrier = ContactProblem(base, ContactOptions(D, curve="spline", formulation="integral"))
    barrier_report = analyse(barrier.stability_view(), q, lam)
    barrier_dense = dense_reduced_eigenvalues(barrier, q, lam)
    positions, label = contacts(barrier, q, lam)
    row = {"branch": branch.name, "index": i, "excess_link": excess_link,
           "barrier_stored": int(branch.unstable_count[i]),
           "barrier": barrier_report.unstable_count,
           "barrier_certified": barrier_report.certified,
           "barrier_dense": int(np.sum(barrier_dense < -ZERO_TOLERANCE)),
           "barrier_lowest": float(barrier_dense[0]), "barrier_contacts": label}
    for curve in ("spline", "polygon"):
        hard, res, mode = hard_contact(base, q, D, curve,
                                       minimise=int(branch.unstable_count[i]) == 0)
        if hard is None:
            row[curve] = {"message": res.message}
        else:
            row[curve] = hard_contact_row(base, hard, res, q, positions, excess_link) | {
                "mode": mode}
        if "count" in row["spline"]:
            break
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nodes", type=int, default=132)
    parser.add_argument("--branches", type=Path, default=Path("/tmp/hc"),
                        help="folder of the saved branches (computed and saved if absent)")
    parser.add_argument("--stable", type=int, default=5, help="count-0 points per branch")
    parser.add_argument("--unstable", type=int, default=2, help="count >= 1 points per branch")
    parser.add_argument("--all", action="store_true", help="every point of the three branches")
    args = parser.parse_args()

    family = branches(args.nodes, args.branches)
    rows = []
    start = time.perf_counter()
    for name in ("beta_contact", "beta_II-", "beta_II+"):
        branch = family[name]
        points = (list(range(len(branch))) if args.all
                  else chosen_points(branch, args.stable, args.unstable))
        if name == "beta_contact":
            points = sorted(set(points) | set(onset_window(branch)))
        for i in points:
            rows.append(check_state(branch, i, args.nodes))
    print(f"N = {args.nodes}: {len(rows)} states in {time.perf_counter() - start:.1f} s\n")
    print_table(rows, args.nodes)


def _count(h: dict) -> str:
    """``analyse / dense`` (an uncertified inertia marked ``*``, analyse's own warning)."""
    return f"{h['count']}{'' if h['certified'] else '*'} / {h['dense']}"


def print_table(rows: list[dict], n: int) -> None:
    """The markdown table of the rows of a ring of ``n`` nodes (hard contact on the spline;
    the polygon's where the spline's was not solved), then the failures and a summary."""
    print("| branch [point] | ΔLk | barrier count: stored / analyse / dense | hard count: "
          "analyse / dense | smallest reduced eigenvalue: barrier / hard | contacts: barrier "
          "/ hard | smallest multiplier (weak) | KKT residual | contact shift / h: hard to "
          "barrier / barrier to hard | "
          "moved / D | Lk error |")
    print("|" + "---|" * 11)
    for r in rows:
        h = r["spline"] if "count" in r["spline"] else r.get("polygon", {})
        junctions = f" ({h['junctions']} at a junction)" if h.get("junctions") else ""
        barrier = (f"{r['barrier_stored']} / {r['barrier']}"
                   f"{'' if r['barrier_certified'] else '*'} / {r['barrier_dense']}")
        head = f"| {r['branch']} [{r['index']}] | {r['excess_link']:.4f} | {barrier} | "
        if "count" not in h:
            print(head + "not solved | " + f"{r['barrier_lowest']:.4g} / - | "
                  f"{r['barrier_contacts']} / - | - | - | - | - | - |")
            continue
        curve = "" if h is r["spline"] else (" (polygon" + (", minimised" if h["mode"] ==
                                                           "minimize" else "") + ")")
        print(head + f"{_count(h)}{curve} | {r['barrier_lowest']:.4g} / {h['lowest']:.4g} | "
              f"{r['barrier_contacts']} / {h['contacts']}{junctions} | {h['min_force']:.3g} "
              f"({h['weak']}) | {h['kkt']:.1e} | {h['shift_to_barrier'] * n:.2f} / "
              f"{h['shift_from_barrier'] * n:.2f} | "
              f"{h['moved_over_D']:.2f} | {h['link_error']:.0e} |")
    for r in rows:
        for curve in ("spline", "polygon"):
            h = r.get(curve)
            if h is None:
                continue
            if "count" not in h:
                print(f"{r['branch']} [{r['index']}], {curve}: not solved: {h['message']}")
            elif h["penetration"] > 1e-4 or h["link_error"] > 1e-8:
                print(f"{r['branch']} [{r['index']}], {curve}: penetration "
                      f"{h['penetration']:.1e} D, |Tw + Wr - ΔLk| {h['link_error']:.1e}")
    solved = [r for r in rows if "count" in r["spline"]]
    agree = sum(r["barrier_stored"] == r["spline"]["count"] for r in solved)
    dense = sum(r["barrier_dense"] == r["spline"]["dense"] for r in solved)
    oracle = sum(r["spline"]["count"] == r["spline"]["dense"] for r in solved)
    print(f"hard contact on the spline solved at {len(solved)} of {len(rows)} states; there "
          f"barrier count = hard count at {agree} (stored / analyse), {dense} (dense / "
          f"dense); analyse = dense oracle at {oracle}")


if __name__ == "__main__":
    main()
