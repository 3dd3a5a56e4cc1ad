"""An independent cross-check of crash: the equations of docs/theory.md and
docs/theory-contact.md written once more in Python (numpy), distributed over MPI ranks
the way crash's master distributes body groups (docs/architecture-cluster.md).

Modules: `scene` (scene files), `mesh` (generators, Gmsh reader), `body` (masses,
constraints, integration), `elements` (triangle and quad kernels), `contact` (search and
penalty), `group` (the one-step pipeline), `meim` (interaction graph, placement), `run`
(the MPI time loop), `output` (energy.csv, contacts.csv, VTU/PVD), `vtu` (reader).
"""
