//! crash-cli: The crash command: run, check, render, study, bench.
