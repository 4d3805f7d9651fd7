//! Everything a pedomatch run writes. The third pipeline crate (docs/architecture.md): its
//! writers are sinks of the run engine's events (`pedo_track::SequenceSink`): the tables as the
//! events come, the figures, the report and the animation from the run the sink gathers.
//!
//! | module | what it writes |
//! |---|---|
//! | [`table`] | a table of [`Cell`]s as CSV or JSON |
//! | [`table_files`] | a table file as CSV or Parquet ([`TableFormat`]), whole or row by row |
//! | [`run_tables`] | the tables of a run: pairs, objects, matches, tracks, frames, reference matches |
//! | [`summary`] | `summary.json`: the input's provenance, the options used, the counts and timings |
//! | [`measure_files`] | the measures of the recording: `peak.npy`, `pti.npy`, `mean.npy`, `measures.json`, `peak.png`, `pti.png` |
//! | [`figure`] | PNG/SVG figures (a matched pair, a run's tracks) and the GIF animation |
//! | [`html_report`] | the self-contained interactive `report.html` of a run or of one pair |
//! | [`register_folder`], [`register_page`] | the folder of `pedomatch register` and its page `register.html` |
//! | [`outdir`] | output folders written whole or not at all |
//! | [`run_folder`] | the folder of one run, through one writer ([`FolderSink`]) whoever runs it |

#![warn(missing_docs)]

pub mod figure;
pub mod html_report;
pub mod measure_files;
pub mod moving_regions;
pub mod outdir;
pub mod register_folder;
pub mod register_page;
pub mod run_folder;
pub mod run_tables;
pub mod summary;
pub mod table;
pub mod table_files;

pub use measure_files::*;
pub use run_folder::*;
pub use run_tables::*;
pub use summary::*;
pub use table::*;
pub use table_files::*;
