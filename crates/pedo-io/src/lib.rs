//! Plantar-pressure recordings in; contours, brightness surfaces and isobaric contours out.
//!
//! - [`read_recording`] reads Tekscan `.asf` and CSV exports, novel emed `.lst`, novel pedar `.asc`
//!   (on a sensor layout), Zebris `.apd`, RSscan/Materialise footscan exports, CSV grids, NumPy
//!   `.npy`/`.npz`, and PNG/TIFF images (single, folder, numbered sequence) into a [`Recording`],
//!   deciding the format by content ([`sniff_format`]);
//! - [`preprocess`] thresholds, smooths and upsamples frames;
//! - [`contour`] extracts closed, counter-clockwise contours (sub-pixel marching squares or the
//!   paper's edge chain) and [`track`] pairs them across frames;
//! - [`surface`] builds the paper's brightness surfaces and [`isobar`] its isobaric contours.
//!
//! Coordinates follow the convention documented in [`grid`]: x = column, y = row, pixel units
//! (sensel centres at integers), or millimetres via [`CoordUnits::Millimetres`].

#![warn(missing_docs)]

pub mod cancel;
pub mod contour;
pub mod drift;
mod error;
pub mod figure;
pub mod formats;
pub mod grid;
pub mod isobar;
pub mod outdir;
pub mod points;

pub mod preprocess;
pub mod recording;
pub mod report;
pub mod sequence;
pub mod study;
pub mod surface;
pub mod synthetic;
pub mod tables;
pub mod track;
pub mod units;

pub use contour::{contour_shapes, contours, Contour, ContourMethod, ContourOptions, Resample};
pub use error::{IoError, Result};
pub use formats::{
    detect_format, parse_bytes, parse_bytes_with, read_recording, read_recording_with,
    sniff_format, ReadOptions,
};
pub use grid::{CoordUnits, Grid};
pub use recording::{Format, FrameMeasures, Recording};
pub use tables::TableFormat;
