"""Implicit Newmark integration (average acceleration) of ``M a + C v + K u = f``, lumped mass.

The trapezoidal rule, Newmark's method with beta = 1/4, gamma = 1/2 (Newmark 1959; Hughes,
*The Finite Element Method*, Sec. 9.1; Belytschko, Liu & Moran, *Nonlinear Finite Elements*,
Sec. 6.3), in its acceleration form with step dt (s)::

    u_p = u + dt v + dt^2/4 a,   v_p = v + dt/2 a                  (predictors)
    (M + dt/2 C + dt^2/4 K) a_new = f_new - K u_p - C v_p          (free DOFs)
    u_new = u_p + dt^2/4 a_new,  v_new = v_p + dt/2 a_new

It is unconditionally stable for linear structures and has no numerical damping: its cost per
step does not follow the elements' critical step, so a structure advanced this way takes the
ice's coupling step without subcycling. The matrix ``A = M + dt/2 C + dt^2/4 K`` of the free DOFs
is factorised once per step size, block by independent block (:mod:`pdfem.fem.block_factor`:
SuperLU's minimum-degree ordering of ``A + A^T``, kept as ``L D L^T``) and each step is two
matrix-vector products (``K u_p``, and ``K u_new``, kept for the supports, the strain energy and
the shaft) and one pair of triangular solves. The blocks may be shared out over the ranks
(:meth:`Newmark.distribute`): each rank then solves its own blocks and computes their rows of
the two products, with the rows of the held nodes that meet only that block (a blade's clamped
root), the ranks share them in one exchange a step, and every rank computes the rows of the held
nodes that meet several blocks: every rank holds the whole state, the serial bits. Accuracy: the
period of a mode of circular frequency omega lengthens by about ``(omega dt)^2 / 12``; 20 steps
per period keep it within 1 % (Hughes, Table 9.1.1 and Eq. 9.1.79), so the modes the coupled
step resolves (the step is the ice's) are integrated as accurately as by the explicit scheme.

Energy. The two update rules give ``u_new - u = dt (v + v_new) / 2``, and with that the change of
``1/2 v . M v + 1/2 u . K u`` over a step is exactly the trapezoidal work
``1/2 (F_n + F_n+1) . (u_new - u)`` of the external forces and the supports' reactions, minus the
damping's ``1/2 (C v_n + C v_n+1) . (u_new - u)`` (>= 0): the balance the explicit integrator
keeps (:mod:`pdfem.fem.explicit`) holds here to round-off with no kinetic correction (the kinetic
energy is ``1/2 v . M v`` itself). An impulse J given by :meth:`Newmark.apply_impulse` changes
the velocity by J / m at an instant, with work ``v . J + J^2 / (2 m)``, as in the explicit
scheme. Dirichlet DOFs follow their prescribed displacement through the same update rules
(their acceleration is what takes them there).

Contact impulses over a step (:meth:`Newmark.end_impulse`). A contact impulse J found during a
step (the ice's contacts, resolved against the surface the step moved) acts on that step as a
force rising from 0 at its start to ``2 J / dt`` at its end: the trapezoidal rule integrates it
into the impulse ``dt/2 (0 + 2 J / dt) = J``. The scheme being linear, the step is amended by the
response to that end force, ``A a' = 2 J / dt``::

    a_new += a',   u_new += dt^2/4 a' = (dt/2) A^-1 J,   v_new += dt/2 a' = A^-1 J

and the force is then taken out of the end acceleration (``a_new -= 2 J / (dt m)`` on the free
DOFs), so the next step starts from ``M a + C v + K u = f`` without it and the impulse acts
once. Only the blocks the impulses touch move: only their solves and their rows of ``K u`` (with
the rows of their held nodes, and of those that meet several blocks) are done again (an ice
contact on one blade amends that blade). Its work is the trapezoidal work of that force,
``J . (u_new - u) / dt``, with the amended ``u_new``: the energy identity above then holds with
it, to round-off. The mean displacement of the step per unit impulse,
``(dt/2) A^-1 / dt = A^-1 / 2``, is the structure's compliance for the contact
(:mod:`pdfem.fem.step_compliance`); as ``dt -> 0`` it is half the explicit scheme's ``M^-1``
(there the impulse is a velocity jump at the substep's start, here a force ramp over the step).

Units as in :mod:`pdfem.fem.explicit`: m, m/s, m/s^2, N, kg, s.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

from pdfem.fem.block_factor import BlockFactor
from pdfem.fem.central_difference_kernels import trapezoid_work
from pdfem.fem.explicit import CentralDifference
from pdfem.fem.step_compliance import Coupling, probe
from pdfem.parallel.comm import SerialComm


class Newmark(CentralDifference):
    """Average-acceleration Newmark integrator (module docstring), the same interface and state
    as :class:`pdfem.fem.explicit.CentralDifference` (whose constructor parameters it takes; the
    safety factor and the eigenvalue do not limit its step).

    Attributes
    ----------
    factorizations
        How many times ``A`` was factorised (once per distinct step size).
    """

    STATE_ARRAYS = ("u", "v", "a", "f_ext", "f_damp")
    """Names of the DOF vectors of the state (no mid-step velocity: the scheme has none)."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._lu: BlockFactor | None = None
        self._lu_dt = math.nan
        self._comm = SerialComm()
        self._a_fc: sp.csr_matrix | None = None
        self._free_idx = np.flatnonzero(self.free)
        self._free_index = np.full(self.n, -1, dtype=np.int64)
        self._free_index[self._free_idx] = np.arange(self._free_idx.size)
        self.factorizations = 0
        self._last = None            # the last step's start (for end_impulse)
        self._step_impulse = None    # N s, the contact impulses on the last step
        self._step_contact_work = 0.0

    def critical_time_step(self) -> float:
        """``inf``: the average-acceleration scheme is unconditionally stable."""
        return math.inf

    def stable_time_step(self) -> float:
        """``inf`` (:meth:`critical_time_step`)."""
        return math.inf

    def kinetic_correction(self) -> float:
        """0 J: the scheme conserves ``1/2 v . M v + 1/2 u . K u`` itself."""
        return 0.0

    def apply_impulse(self, dofs: np.ndarray, impulse: np.ndarray) -> None:
        """Give the DOFs ``dofs`` the impulses ``impulse`` (N s) now: their velocity jumps by
        impulse / mass; with damping, the damping force and the acceleration follow the new
        velocity (so the next step's damping loss, ``dt/4 (v + v_new) . C (v + v_new)``, is
        never negative)."""
        super().apply_impulse(dofs, impulse)
        if self.alpha or self.beta:
            old = self.f_damp
            self.f_damp = self._damping_force(self.v)
            self.a[self.free] += ((old - self.f_damp) / self.m)[self.free]

    def distribute(self, comm) -> None:
        """Share the steps over the ranks of ``comm``: each factorises and solves its own
        independent blocks of ``A`` (:class:`pdfem.fem.block_factor.BlockFactor`) and computes
        their rows of the stiffness products, and every rank holds the same state bit for bit.
        Collective from then on: every rank steps."""
        self._comm = comm
        self._lu, self._lu_dt = None, math.nan

    def _factorize(self, dt: float) -> None:
        """Factorise ``A = (1 + alpha dt/2) M + (beta dt/2 + dt^2/4) K`` on the free DOFs."""
        A = (sp.diags((1.0 + 0.5 * self.alpha * dt) * self.m)
             + (0.5 * self.beta * dt + 0.25 * dt * dt) * self.K).tocsc()
        rows = A[self._free_idx]
        self._lu = BlockFactor(rows[:, self._free_idx], self._comm)
        self._a_fc = rows[:, self.fixed].tocsr() if self.fixed.size else None
        self._lu_dt = dt
        self.factorizations += 1
        self._block_rows()

    def _block_rows(self) -> None:
        """Where each block of ``A`` sits: its DOFs and nodes, the block of each DOF (-1: held),
        the nodes whose rows of the products a block's rank computes (its own, and the held
        nodes whose rows meet that block only) and their DOFs, the held nodes whose rows meet
        several blocks (or none: every rank computes them), and this rank's blocks' nodes."""
        self._block_dofs = [self._free_idx[idx] for idx in self._lu.blocks]
        self._block_nodes = [np.unique(dofs // 3).astype(np.int64) for dofs in self._block_dofs]
        self._dof_block = np.full(self.n, -1, dtype=np.int64)
        for k, dofs in enumerate(self._block_dofs):
            self._dof_block[dofs] = k
        held = np.unique(self.fixed // 3).astype(np.int64)
        met = self._block_met(held)
        self._row_nodes = [np.union1d(nodes, held[met == k])
                           for k, nodes in enumerate(self._block_nodes)]
        self._row_dofs = [self._dofs_of(nodes) for nodes in self._row_nodes]
        self._held_nodes = held[met < 0]
        self._my_nodes = self._nodes_of(self._block_nodes, self._lu.dealt.mine)
        # floats a block sends in a step's exchange: its solution, its rows of K u (and of the
        # companion's product)
        self._exchange_sizes = [len(d) + len(r) * (1 if self._pair is None else 2)
                                for d, r in zip(self._block_dofs, self._row_dofs)]

    def _block_met(self, nodes: np.ndarray) -> np.ndarray:
        """(N,) the one block that the rows of ``nodes`` in ``K`` (and in the companion) meet,
        -1 where they meet several or none."""
        dofs = self._dofs_of(nodes)
        of = np.repeat(np.arange(len(nodes)), 3)[:len(dofs)]
        lo = np.full(len(nodes), len(self._block_dofs), dtype=np.int64)
        hi = np.full(len(nodes), -1, dtype=np.int64)
        for mat in [self.k_op.matrix] + ([] if self._pair is None else [self._pair.b.matrix]):
            sub = mat[dofs].tocoo()
            block = self._dof_block[sub.col]
            node = of[sub.row][block >= 0]
            np.minimum.at(lo, node, block[block >= 0])
            np.maximum.at(hi, node, block[block >= 0])
        return np.where(lo == hi, hi, -1)

    def _dofs_of(self, nodes: np.ndarray) -> np.ndarray:
        """The DOFs ``3 i .. 3 i + 2`` of the ascending ``nodes``, those below ``n`` (a DOF
        count that is not a multiple of 3 has no node blocks: its rows are computed whole)."""
        dofs = (3 * nodes[:, None] + np.arange(3)).ravel()
        return dofs[dofs < self.n]

    def add_companion(self, op) -> None:
        """:meth:`pdfem.fem.explicit.CentralDifference.add_companion`; the held nodes' blocks
        are found again with its pattern."""
        super().add_companion(op)
        if self._lu is not None:
            self._block_rows()

    @staticmethod
    def _nodes_of(lists: list, blocks) -> np.ndarray:
        """The nodes (int64) of ``lists`` (one per block) of ``blocks``, one after the other (a
        node in two lists, its DOFs in two blocks, is listed twice: its rows are computed
        twice, to the same bits)."""
        return np.concatenate([lists[k] for k in blocks] or [np.zeros(0, dtype=np.int64)])

    def _rhs_product(self, x: np.ndarray) -> np.ndarray:
        """``K x`` on the rows of this rank's blocks (the others zero: their solves are other
        ranks'); every row on one rank."""
        if not self._lu.dealt.shared:
            return self.k_op @ x
        out = np.zeros(self.n)
        self.k_op.rows(x, self._my_nodes, out)
        return out

    def _solved(self, r: np.ndarray, x: np.ndarray, state, blocks: np.ndarray | None = None,
                old: tuple | None = None) -> tuple[np.ndarray, np.ndarray, tuple]:
        """Solve ``A y = r`` (free DOFs) into the free DOFs of ``x`` (n,), and the products
        ``K u``, ``K_sigma u`` of the displacement ``u = state(x)`` (element by element), on
        every rank: each rank solves its blocks (all, or those of ``blocks``, outside which
        ``r`` is zero and ``u`` has not changed since the products ``old``, whose other rows
        are kept) and computes their rows (with those of the held nodes that meet only them), the
        ranks share them in one exchange, then the rows of the held nodes that meet several
        blocks. Returns ``x``, ``u`` and the products: the bits
        of a whole solve and whole products."""
        lu = self._lu
        if blocks is None and not lu.dealt.shared:
            x[self._free_idx] = lu.solve(r)
            u = state(x)
            return x, u, self._products(u)
        y, mine = lu.solve_mine(r, blocks)
        x[self._free_idx] = y
        u = state(x)
        if old is None:
            ku, cu = np.empty(self.n), None if self._pair is None else np.empty(self.n)
        else:
            ku, cu = old[0].copy(), None if old[1] is None else old[1].copy()
        self._rows(u, self._nodes_of(self._row_nodes, mine), ku, cu)
        dofs, rows = self._block_dofs, self._row_dofs
        parts = [np.concatenate([y[lu.blocks[k]], ku[rows[k]]]
                                + ([] if cu is None else [cu[rows[k]]])) for k in mine]
        for k, part in lu.dealt.everyone_arrays(parts, self._exchange_sizes, blocks):
            n_y, n_r = len(dofs[k]), len(rows[k])
            x[dofs[k]], ku[rows[k]] = part[:n_y], part[n_y:n_y + n_r]
            if cu is not None:
                cu[rows[k]] = part[n_y + n_r:]
        u = state(x)
        if self._held_nodes.size:
            self._rows(u, self._held_nodes, ku, cu)
        return x, u, (ku, cu)

    def _rows(self, u: np.ndarray, nodes: np.ndarray, ku: np.ndarray, cu) -> None:
        """The rows of ``nodes`` of ``K u`` into ``ku`` (and of the companion's into ``cu``)."""
        if cu is None:
            self.k_op.rows(u, nodes, ku)
        else:
            self._pair.rows(u, nodes, ku, cu)

    def step(self, dt: float, f_ext: np.ndarray | None = None) -> None:
        """Advance the state by ``dt`` (s) with the external force ``f_ext`` (N) at the new time.

        Parameters
        ----------
        dt
            Time step (s), any size (accuracy: module docstring).
        f_ext
            (n,) external force DOF vector at ``time + dt``; default zero.
        """
        if dt != self._lu_dt:
            self._factorize(dt)
        t_new = self.time + dt
        q = 0.25 * dt * dt
        u_p = self.u + dt * self.v + q * self.a
        v_p = self.v + 0.5 * dt * self.a
        f = self._zero if f_ext is None else np.array(f_ext, dtype=np.float64)
        # K u_p + C v_p with one product: (K (u_p + beta v_p) + alpha m v_p)
        rhs = f - self._rhs_product(u_p + self.beta * v_p if self.beta else u_p)
        if self.alpha:
            rhs -= self.alpha * self.m * v_p
        a_new = np.empty(self.n)
        r = rhs[self._free_idx]
        if self.fixed.size:
            g = self._dirichlet(t_new)
            a_c = (g - u_p[self.fixed]) / q
            a_new[self.fixed] = a_c
            if np.any(a_c):
                r = r - self._a_fc @ a_c

        def displacement(a: np.ndarray) -> np.ndarray:
            u = u_p + q * a
            if self.fixed.size:
                u[self.fixed] = g  # exactly, not to round-off
            return u

        a_new, u_new, (ku, cu) = self._solved(r, a_new, displacement)
        v_new = v_p + 0.5 * dt * a_new
        f_damp_old = self.f_damp
        self.f_damp = self._damping_force(v_new)
        self._last = (self.u, self.f_ext, f_damp_old, self._reaction,
                      (self.work_external, self.work_supports, self.damping_dissipated))
        self._step_impulse, self._step_contact_work = None, 0.0
        self._book_work(u_new - self.u, f, f_damp_old, ku if self._supports_move else None,
                        a_new)
        self._advance(dt, u_new, v_new, a_new, v_new, f)   # no mid-step velocity: v_half = v
        self._ku, self._cu = ku, cu

    steps_before_contact = True
    """A step is taken first and the contacts over it amend it (:meth:`end_impulse`)."""

    def contact_impulse(self, dofs: np.ndarray, impulse: np.ndarray) -> float:
        """Contact impulses on the step just taken: :meth:`end_impulse`."""
        return self.end_impulse(dofs, impulse)

    def end_impulse(self, dofs: np.ndarray, impulse: np.ndarray) -> float:
        """Amend the step just taken by contact impulses ``impulse`` (N s) on the DOFs ``dofs``
        acting over it, as a force rising to ``2 J / dt`` at its end (module docstring); those
        on Dirichlet DOFs go to their supports. The step's works are booked again with the
        amended state.

        Returns
        -------
        float
            The work (J) the impulses add to the step's contact work, ``J . (u_new - u) / dt``
            with every impulse given to this step so far (the increment over the earlier
            calls), so that the sum of the returns is the step's contact work.
        """
        if self._last is None:
            raise RuntimeError("end_impulse needs a step to amend: take a step first")
        u_old, f_old, f_damp_old, reaction_old, works = self._last
        dt = self.last_dt
        j = np.zeros(self.n)
        np.add.at(j, dofs, np.asarray(impulse, dtype=np.float64))
        j[self.fixed] = 0.0
        force = (2.0 / dt) * j
        touched = np.unique(self._dof_block[np.flatnonzero(j)])   # the blocks it moves
        touched = touched[touched >= 0]
        u_old_end = self.u
        da, self.u, (self._ku, self._cu) = self._solved(
            force[self._free_idx], np.zeros(self.n), lambda d: u_old_end + 0.25 * dt * dt * d,
            touched, (self._ku, self._cu))
        self.v = self.v + 0.5 * dt * da
        self.v_half = self.v
        self.a = self.a + da - force / self.m
        f_new = self.f_ext
        self.f_ext, self._reaction = f_old, reaction_old
        self.work_external, self.work_supports, self.damping_dissipated = works
        self.f_damp = self._damping_force(self.v)
        self._book_work(self.u - u_old, f_new, f_damp_old,
                        self._ku if self._supports_move else None, self.a)
        self.f_ext = f_new
        self._step_impulse = j if self._step_impulse is None else self._step_impulse + j
        total = trapezoid_work(self._step_impulse, self._step_impulse, self.u, u_old) / dt
        added = total - self._step_contact_work
        self._step_contact_work = total
        return added

    def compliance_blocks(self, dt: float, node_dofs: np.ndarray, points: np.ndarray,
                          length: float) -> Coupling:
        """The blocks (1/kg) of ``A^-1`` for the step ``dt`` (s) between the nodes whose x, y,
        z DOFs are the rows of ``node_dofs`` (m apart at ``points``), within a few decay
        lengths ``length`` (m) (zero rows and columns on Dirichlet DOFs), by probing
        (:func:`pdfem.fem.step_compliance.probe`); with the blocks shared over ranks, each
        rank solves its own blocks' probes and reads their rows, which go to every rank."""
        if dt != self._lu_dt:
            self._factorize(dt)
        lu = self._lu
        if not lu.dealt.shared:
            return probe(lu.solve, self._free_index, node_dofs, points, length)
        def complete(blocks: np.ndarray, rows: np.ndarray) -> None:
            """Each rank solved its own blocks: the rows read there go to every rank."""
            block = np.where(rows >= 0, self._dof_block[self._free_idx[np.maximum(rows, 0)]], -1)
            parts = [blocks[block == k] for k in lu.dealt.mine]
            for k, part in lu.dealt.everyone(parts):
                blocks[block == k] = part

        return probe(lambda b: lu.solve_mine(b)[0], self._free_index, node_dofs, points,
                     length, complete)
