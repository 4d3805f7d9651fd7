//! Plantar-pressure recordings in; the shapes of one frame out. The first pipeline crate of
//! pedomatch (docs/architecture.md): it knows files and frames, not runs.
//!
//! - [`read_recording`] reads Tekscan `.asf` and CSV exports, novel emed `.lst`, novel pedar `.asc`
//!   (on a sensor layout), Zebris `.apd`, RSscan/Materialise footscan exports, CSV grids, NumPy
//!   `.npy`/`.npz`, and PNG/TIFF images (single, folder, numbered sequence) into a [`Recording`],
//!   deciding the format by content ([`sniff_format`]); [`units`] applies stated or overridden
//!   units; [`recording::FrameSource`] hands a long file's frames window by window to a run that
//!   streams;
//! - [`preprocess`] thresholds, smooths and upsamples frames;
//! - [`contour`] extracts closed, counter-clockwise contours (sub-pixel marching squares or the
//!   paper's edge chain), [`surface`] builds the paper's brightness surfaces and [`isobar`] its
//!   isobaric contours: the objects of one frame that the run engine (`pedo-track`) matches;
//! - [`points`] reads and writes point files, [`regions`] the points and region masks a user
//!   marks to be followed through a stance, [`synthetic`] makes recordings with a known motion;
//! - [`IoError`] is the one error enum of the pipeline crates (this one, `pedo-track`,
//!   `pedo-output` and `pedo-study`), and [`cancel::Cancel`] the request that stops their work.
//!
//! Coordinates follow the convention documented in [`grid`]: x = column, y = row, pixel units
//! (sensel centres at integers), or millimetres via [`CoordUnits::Millimetres`].

#![warn(missing_docs)]

pub mod cancel;
pub mod contour;
mod error;
pub mod formats;
pub mod grid;
pub mod isobar;
pub mod limits;
pub mod marks;
pub mod measures;
pub mod points;
pub mod preprocess;
pub mod recording;
pub mod regions;
pub mod stances;
pub mod surface;
pub mod synthetic;
pub mod units;
pub mod user_masks;

pub use contour::{contour_shapes, contours, Contour, ContourMethod, ContourOptions, Resample};
pub use error::{counted, IoError, Result};
pub use formats::{
    detect_format, parse_bytes, parse_bytes_with, read_recording, read_recording_with,
    sniff_format, ReadOptions,
};
pub use grid::{CoordUnits, Grid};
pub use recording::{
    FootColumns, Format, FrameMeasures, FrameSource, FrameStore, Recording, StoredValues,
    FRAME_WINDOW,
};
