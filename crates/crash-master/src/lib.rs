//! crash-master: The master: global time loop, MEIM (petgraph), grouping, assignment, output merge.
