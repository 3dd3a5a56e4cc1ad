//! crash-io: Results: VTU/PVD series, CSV histories, PNG pictures and plots, checkpoints.
