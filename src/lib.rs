//! appell: simulate, fit and plan experiments on a Painleve-Appell friction rig.
//!
//! The data flows through the modules in this order: `model` (rig, modes, contact forces,
//! regions) -> `sim` (Runge-Kutta with dense output, events, hybrid runs) -> `data`
//! (recordings in and out) -> `fit` -> `plan` -> `report`.
#![warn(missing_docs)]

pub mod bench;
pub mod data;
pub mod fit;
pub mod model;
pub mod output;
pub mod plan;
pub mod report;
pub mod scene;
pub mod sim;
