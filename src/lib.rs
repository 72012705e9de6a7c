//! appell: simulate, fit and plan experiments on a Painleve-Appell friction rig.
//!
//! The modules follow the data, and none imports from one below it in this list:
//! - `model/`: the rig (`rig.rs`, the rigid pendulum in `pendulum.rs`), modes (`mode.rs`), the
//!   contact forces and both models' accelerations (`forces.rs`), transitions from rest
//!   (`transition.rs`), the regions and the paradox band (`regions.rs`), where the markers are
//!   (`markers.rs`). One formula, one place, generic over `f64` and dual numbers.
//! - `sim/`: Runge-Kutta steppers with dense output (`rk.rs`, `tableau.rs`: DP5 and DOP853) and the
//!   hybrid run (`hybrid/`: take a step, check the guards, locate the event, decide the next mode,
//!   jump, emit samples), returning a solution with its events and statistics.
//! - `scene.rs`: scene and rig files (TOML), checked key by key.
//! - `numbers.rs`: numbers as text reports print them (a value with its uncertainty to the
//!   digits the uncertainty carries).
//! - `output.rs`: writing files whole (temporary file and rename) and never over an input.
//! - `data/`: recordings in and out: the CSV family one file per tool (`table/`), HDF5
//!   (`hdf5/`), XML (`tracker_project.rs`, `kinovea_xml.rs`), MCAP (`mcap/`), calibration into the
//!   rail frame (`calibrate.rs`), the one `Recording` type and the canonical CSV
//!   (`recording.rs`), synthetic recordings (`synth.rs`), what a file holds before its options
//!   are known (`inspect/`).
//! - `fit/`: the estimation problem (`problem/`), the Levenberg-Marquardt solver for argmin
//!   (`lm.rs`), the nuisances chosen by the data (`select/`), the uncertainty and adequacy checks,
//!   and many releases fitted together (`joint/`).
//! - `plan/`: plan files (`spec.rs`), observability criteria (`criteria.rs`), the search
//!   (`search.rs`) and the prior from an earlier fit (`prior.rs`).
//! - `report/`: tables, JSON and figures (`plot.rs` renders SVG and PNG with the shipped font).
//! - `pipeline/`: what a command does between its flags and its output (the options by their
//!   CLI names, read and check, fit, provenance), shared by the binary and the Python package.
//! - `bench/`: the benchmarks `appell bench` runs.
//! - `cli/` (in the binary): clap derive structs and one function per command.
#![warn(missing_docs)]

pub mod bench;
pub mod cpu;
pub mod data;
pub mod fit;
pub mod model;
pub mod numbers;
pub mod output;
pub mod pipeline;
pub mod plan;
pub mod report;
pub mod scene;
pub mod sim;
