"""Case texts shared by tests of several packages.

``CYLINDER``: the seed's rigid cylinder striking an ice plate that breaks (coarsened: dx 2 cm,
4.1 GPa ice with a low fracture energy so that it cracks within 1.2 ms), the MPI tests'
coupled case (tests/run/test_mpi_run.py, tests/forces/test_mpi_short_range.py). SI units.
``CYLINDER_BODIES`` is its plate and cylinder without the ``[run]`` section, for tests that
run them otherwise (tests/run/test_mpi_checkpoint_ranks.py: floating, with checkpoints).
``BLOCK``: a 6 cm ice cube (216 particles, dx 1 cm) on a fixed base, its top layer pushed down
at 0.5 m/s for 20 us (three frames): elastic, no structure, no meshing; the loads are the
reactions ``block.base`` and ``block.top`` (tests/api, tests/study: runs of a second or less).
``PANEL_BODIES``: an ice floe pushed at 1 m/s against the elastic hull panel (coarse, first
contact within 0.2 ms), without the ``[run]`` section (tests/run/test_mpi_run.py,
tests/output/test_paraview.py).
``TWO_CUBES``: two 5 cm ice cubes (125 particles each) meeting at 4 m/s with short-range
contact, breaking about half their bonds in 4 ms (1,583 coupling steps, 9 frames): the tiny
run of the stop-signal and write-error tests (tests/run/test_stop.py,
tests/run/test_write_errors.py).
"""

CYLINDER_RUN = """
[run]
end_time = 1.2e-3
output_interval = 4.0e-4
"""

CYLINDER_BODIES = """
[[ice]]
name = "plate"
dx = 0.02
shape = { box = { min = [0.0, 0.0, 0.0], max = [1.0, 0.5, 0.04] } }
material = { density = 900.0, youngs_modulus = 4.1e9, poisson_ratio = 0.3, fracture_energy = 3.0 }
[[structure]]
name = "cylinder"
kind = "rigid"
mesh = "indenters"
params = { shape = "cylinder", radius = 0.1, length = 0.1, axis = "z", center_x = 0.5, center_y = 0.5905, center_z = 0.02, element_size = 0.02 }
motion = { velocity = [0.0, -4.0, 0.0] }
"""

CYLINDER = CYLINDER_RUN + CYLINDER_BODIES

BLOCK = """
[run]
end_time = 2.0e-5
output_interval = 1.0e-5

[[ice]]
name = "block"
dx = 0.01
shape = { box = { min = [0.0, 0.0, 0.0], max = [0.06, 0.06, 0.06] } }
material = { density = 900.0, youngs_modulus = 4.0e9, poisson_ratio = 0.3, fracture_energy = 10.0 }
fixed = [ { name = "base", box = { min = [-0.01, -0.01, -0.01], max = [0.07, 0.07, 0.01] } } ]
prescribed_velocity = [ { name = "top", region = { box = { min = [-0.01, -0.01, 0.05], max = [0.07, 0.07, 0.07] } }, velocity = [0.0, 0.0, -0.5] } ]
"""

PANEL_BODIES = """
[[ice]]
name = "floe"
dx = 0.04
shape = { box = { min = [0.8, 0.4, -0.019999], max = [1.2, 0.8, 0.140001] } }
material = { fracture_energy = 10.0 }
prescribed_velocity = [ { region = { box = { min = [0.7, 0.3, 0.09], max = [1.3, 0.9, 0.2] } }, velocity = [0.0, 0.0, -1.0], ramp_time = 2.0e-4 } ]
[[structure]]
name = "panel"
mesh = "hull_panel"
params = { element_size = 0.12 }
fixed_groups = ["fixed"]
"""

TWO_CUBES = """
[run]
end_time = 4.0e-3
output_interval = 5.0e-4
short_range_contact = true

[[ice]]
name = "a"
dx = 0.01
shape = { box = { min = [0.0, 0.0, 0.0], max = [0.05, 0.05, 0.05] } }
material = { density = 900.0, youngs_modulus = 4.1e9, poisson_ratio = 0.3, fracture_energy = 10.0 }
initial_velocity = [0.0, 0.0, 2.0]

[[ice]]
name = "b"
dx = 0.01
shape = { box = { min = [0.0, 0.0, 0.0505], max = [0.05, 0.05, 0.1005] } }
material = { density = 900.0, youngs_modulus = 4.1e9, poisson_ratio = 0.3, fracture_energy = 10.0 }
initial_velocity = [0.0, 0.0, -2.0]
"""
