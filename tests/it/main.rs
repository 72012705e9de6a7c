//! Integration tests: one binary, shared helpers, one module per capability.

mod cli_simulate;
mod helpers;
mod simulate_oracles;
