"""FE model fast paths against dense SciPy baselines measured in the same run.

For the 12 × 8 and 24 × 18 plates (issue 2):
* assembling K from a parameter vector: bwim's per-element unit matrices and one bincount
  into banded storage, against re-integrating every element and scattering into a dense
  matrix;
* factorising K and solving for 18 sensor channels: banded Cholesky against dense
  Cholesky (``scipy.linalg.cho_factor``);
* the lowest 20 modes: shift-invert Lanczos with the banded factor against dense
  ``scipy.linalg.eigh(K, M, subset_by_index=...)``.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

import bwim
from benchmarks._timing import median_time, print_table
from bwim.fe.plate import bfs_unit_matrices, flexural_rigidity


def _bridge(nx: int, ny: int) -> bwim.Bridge:
    return bwim.Bridge.plate(length=12.0, width=8.0, nx=nx, ny=ny, thickness=0.65, E=35e9,
                             mu=1560.0, zones=(nx, ny))


def _sensors() -> list[bwim.Sensor]:
    return [bwim.Sensor(x=x, y=y, kind=k) for k in ("strain_x", "strain_y")
            for x in (3.0, 6.0, 9.0) for y in (2.0, 4.0, 6.0)]


def _dense_assembly(bridge: bwim.Bridge, E_x: np.ndarray, E_y: np.ndarray) -> np.ndarray:
    model = bridge.model
    g = model.grid
    a, b = g.element_sizes()
    K = np.zeros((g.n_dof, g.n_dof))
    for e, dofs in enumerate(g.element_dofs()):
        kxx, kyy, kxy, _ = bfs_unit_matrices(a[e], b[e], model.poisson)
        dx = flexural_rigidity(E_x[e], model.thickness, model.poisson)
        dy = flexural_rigidity(E_y[e], model.thickness, model.poisson)
        K[np.ix_(dofs, dofs)] += dx * kxx + dy * kyy + np.sqrt(dx * dy) * kxy
    free = model.assembler.free
    return K[np.ix_(free, free)]


MESHES = ((12, 8), (24, 18))


def _unband(ab: np.ndarray) -> np.ndarray:
    n = ab.shape[1]
    out = np.zeros((n, n))
    for d in range(ab.shape[0]):
        idx = np.arange(n - d)
        out[idx + d, idx] = ab[d, : n - d]
    return out


def _mesh_rows(nx: int, ny: int, rng: np.random.Generator, timed) -> list[list[object]]:
    bridge = _bridge(nx, ny)
    n = bridge.n_zones
    E_x, E_y = rng.uniform(30e9, 40e9, n), rng.uniform(30e9, 40e9, n)
    trial = bridge.with_params(E_x=E_x, E_y=E_y)
    model = bridge.model
    params = trial.params
    S = bridge.sensor_matrix(_sensors())
    label = f"{nx}×{ny} ({bridge.n_free} DOF, bw {model.assembler.bandwidth})"
    rows = []

    def fast_assembly():
        return model.assembler.stiffness_banded(model.stiffness_coefficients(params))

    def dense_assembly():
        return _dense_assembly(bridge, E_x, E_y)

    Kd = dense_assembly()
    np.testing.assert_allclose(np.tril(Kd), np.tril(_unband(fast_assembly())),
                               atol=1e-10 * abs(Kd).max())
    ab = fast_assembly()

    def banded_solve():
        c = sla.cholesky_banded(ab, lower=True)
        return sla.cho_solve_banded((c, True), S.T)

    def dense_solve():
        return sla.cho_solve(sla.cho_factor(Kd, lower=True), S.T)

    ref = dense_solve()
    np.testing.assert_allclose(banded_solve(), ref, rtol=1e-8, atol=1e-12 * abs(ref).max())
    Md = bridge.mass_matrix().toarray()

    def fast_modes():
        fresh = bridge.with_params(E_x=E_x, E_y=E_y)  # no cached factor or modes
        return fresh.modes(20).omega

    def dense_modes():
        return np.sqrt(sla.eigh(Kd, Md, eigvals_only=True, subset_by_index=[0, 19]))

    np.testing.assert_allclose(fast_modes(), dense_modes(), rtol=1e-8)
    for name, fast, base, fmt in (
        ("assemble K(p)", fast_assembly, dense_assembly, ".3f"),
        ("factor + 18 solves", banded_solve, dense_solve, ".3f"),
        ("lowest 20 modes", fast_modes, dense_modes, ".2f"),
    ):
        t_fast = timed(fast)
        t_base = timed(base, rep=3)
        rows.append([label, name, format(t_fast * 1e3, fmt), format(t_base * 1e3, fmt),
                     f"{t_base / t_fast:.1f}×"])
    return rows


def run(meshes=MESHES, *, repeat: int = 7, min_time: float = 0.05) -> list[list[object]]:
    """Time every operation on every mesh; returns the table rows.

    Each fast path is checked against its baseline's answer before it is timed.
    """
    rng = np.random.default_rng(0)

    def timed(fn, rep=repeat):
        return median_time(fn, repeat=min(rep, repeat), min_time=min_time)

    return [row for nx, ny in meshes for row in _mesh_rows(nx, ny, rng, timed)]


def main() -> None:
    rows = run()
    print_table("FE model: bwim fast paths vs dense SciPy baselines (median wall time, ms)",
                ["mesh", "operation", "bwim", "dense baseline", "speed-up"], rows)


if __name__ == "__main__":
    main()
