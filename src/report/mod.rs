//! Reports: readable timelines, JSON objects and CSV tables, each written whole or not at all.

pub mod fit;
pub mod joint;
pub mod plan;
pub mod plot;
pub mod regions;
mod simulate;

pub use simulate::{simulation_json, timeline, write_trajectory_csv};
