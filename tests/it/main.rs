//! Integration tests: one binary, shared helpers, one module per capability.

mod cli_fit;
mod cli_regions;
mod cli_simulate;
mod fit;
mod hardening;
mod helpers;
mod paradox;
mod plan;
mod real_files;
mod recordings;
mod regions;
mod simulate_oracles;
mod stress;
