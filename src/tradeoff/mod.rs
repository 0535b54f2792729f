//! The speed–accuracy trade-off study behind `specula tradeoff`: knob sweeps, one row per
//! (method, knob values) with its median GPU time per pass and its errors against the
//! exact reference, the Pareto front of (time, error), `tradeoff.csv` and an SVG plot.
//! [`run`] drives the rendering (the CLI only parses its arguments and prints the table);
//! everything else here is plain data, so it is tested alone.
//!
//! One job per file: `sweep.rs` (knob sweeps and their variants), `rows.rs` (rows, the
//! metric, the Pareto front, the panels), `csv.rs`, `plot.rs` (the figure, its point
//! labels in `labels.rs` and its axes' ticks in `ticks.rs`) and `study.rs` (the driver).

pub mod calibrate;
pub mod corpus;
mod csv;
mod labels;
mod plot;
mod rows;
mod scatter;
mod study;
mod sweep;
mod ticks;

pub use calibrate::{calibrate, calibrate_measured, costs_for, Source};
pub use corpus::{gpu_methods, measure, reference_quality, Measure};
pub use csv::csv;
pub use labels::{place_labels, PixelRect};
pub(crate) use plot::write_bitmap_png;
pub use plot::{plot, Figure};
pub use rows::{pareto_front, region_panels, Metric, Panel, Row};
pub use scatter::scatter;
pub use study::{run, Config, Progress, Report};
pub use sweep::{series, variants, Series, Sweep};
