//! Integration tests: one binary, shared helpers, one module per capability.

mod budgets;
mod budgets_files;
mod budgets_mcap;
mod cli_fit;
mod cli_messages;
mod cli_regions;
mod cli_simulate;
mod fit;
mod fit_real;
mod fuzz_structured;
mod hardening;
mod helpers;
mod joint;
mod measured;
mod misspec;
mod outputs;
mod paradox;
mod plan;
mod prefit_checks;
mod real_files;
mod real_rigs;
mod recordings;
mod regions;
mod rigid;
mod simulate_oracles;
mod stress;
