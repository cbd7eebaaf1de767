"""An implicit structure of independent parts (blades on a held hub), its steps and contact
amendments split over 2 ranks (each rank its own parts' solves and stiffness rows), holds the
serial state bit for bit.

Reference: the same :class:`pdfem.fem.implicit.Newmark` on one process, with the same forces and
impulses: displacement, velocity, acceleration, ``K u``, the companion's ``K_sigma u`` and the
works, and the contact compliance probed over the parts, compared with ``numpy.array_equal``
(docs/parallel.md: 1 and N ranks agree; here exactly, since every row and every block is the
same arithmetic wherever it is done). An amendment by an impulse on one part recomputes only
that part's rows and solve (with its held root's, shipped with the part's rows, and the hub's,
which meets every part), which the serial reference checks too, against a whole product.
"""

from __future__ import annotations

import sys
import textwrap
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from pdfem.fem.implicit import Newmark
from pdfem.fem.node_blocks import NodeBlockOperator

from support.mpi import script_says

sys.path.insert(0, str(Path(__file__).parent))
from test_block_factor import blocky_spd  # noqa: E402


def hub_and_blades() -> tuple[sp.csr_matrix, sp.csr_matrix, np.ndarray, np.ndarray]:
    """Stiffness and companion (3 x 3 node blocks) of four parts (7, 5, 9, 6 nodes) that meet
    only at one held node (27, the hub), each also held at a root node of its own (28-31),
    lumped masses, and the held DOFs."""
    a, dofs = blocky_spd(sizes=(7, 5, 9, 6))
    s = np.zeros((NODES, NODES))
    s[:27, :27] = a.toarray()
    for p, d in enumerate(dofs):
        s[27, d[0]] = s[d[0], 27] = -0.5
        s[28 + p, d[-1]] = s[d[-1], 28 + p] = -0.25
        s[28 + p, 28 + p] = 5.0
    s[27, 27] = 10.0
    node = np.array([[2.0, 0.5, 0.1], [0.5, 2.0, 0.3], [0.1, 0.3, 2.0]])
    k = sp.csr_matrix(sp.kron(sp.csr_matrix(s), node) * 1e3)
    companion = sp.csr_matrix(sp.kron(sp.csr_matrix(s), np.eye(3) + 0.1) * -1e2)
    mass = 1.0 + np.arange(N) / N
    return k, companion, mass, np.arange(81, N)


NODES = 32
N = 3 * NODES


def history(comm) -> list[np.ndarray]:
    """A few steps with forces, a contact amendment on part 1 (nodes 7..11), more steps: the
    state and works after each, flattened."""
    k, companion, mass, fixed = hub_and_blades()
    sol = Newmark(k, mass, fixed_dofs=fixed)
    sol.add_companion(NodeBlockOperator(companion))
    sol.distribute(comm)
    rng = np.random.default_rng(3)
    sol.initialize(u=np.where(sol.free, rng.standard_normal(N) * 1e-3, 0.0))
    out = []
    for i in range(6):
        sol.step(1e-3, rng.standard_normal(N))
        if i in (2, 3):
            dofs = np.array([3 * 8, 3 * 8 + 2, 3 * 10 + 1, 82])   # part 1, and the held node
            out.append(np.array([sol.end_impulse(dofs, rng.standard_normal(4) * 1e-3)]))
        out += [sol.u, sol.v, sol.a, sol.stiffness_force(), sol.companion_force(),
                np.array([sol.work_external, sol.work_supports])]
    # the probed compliance of every node (points on a helix, 0.2 m decay length): each rank
    # probes its own parts, the rows read there go to every rank
    nodes = np.arange(NODES)
    points = np.stack([np.cos(nodes), np.sin(nodes), 0.05 * nodes], axis=1)
    c = sol.compliance_blocks(1e-3, 3 * nodes[:, None] + np.arange(3), points, 0.2)
    assert np.any(c.blocks != 0.0)
    return out + [c.start, c.index, c.blocks]


def test_an_amendment_on_one_part_keeps_the_whole_product_s_bits():
    """Serial: after the amendments, ``K u`` and ``K_sigma u`` (only the amended part's rows
    and the held nodes' recomputed) are the whole products of the state."""
    from pdfem.parallel.comm import SerialComm
    k, companion, mass, fixed = hub_and_blades()
    sol = Newmark(k, mass, fixed_dofs=fixed)
    sol.add_companion(NodeBlockOperator(companion))
    sol.distribute(SerialComm())
    sol.initialize()
    sol.step(1e-3, np.ones(N))
    sol.end_impulse(np.array([3 * 8]), np.array([1e-3]))
    assert list(sol._held_nodes) == [27]      # the roots' rows go with their parts' rows
    assert np.array_equal(sol.stiffness_force(), k @ sol.u)
    assert np.array_equal(sol.companion_force(), companion @ sol.u)
    assert np.any(sol.u[3 * 7:3 * 12] != 0.0)


SCRIPT = textwrap.dedent('''
    import sys
    import numpy as np
    sys.path[:0] = [sys.argv[1], sys.argv[2]]
    from test_implicit_ranks import history
    from pdfem.parallel.comm import SerialComm, world
    comm = world()
    split, serial = history(comm), history(SerialComm())
    same = [np.array_equal(a, b) for a, b in zip(split, serial)]
    assert all(same), f"not the serial bits at {same.index(False)}"
    if comm.rank == 0:
        print("ok", len(same))
''')


def test_two_ranks_step_and_amend_their_own_parts_and_agree_with_one_bit_for_bit(tmp_path):
    assert script_says(SCRIPT, 2, tmp_path, __file__) == str(6 * 6 + 2 + 3)
