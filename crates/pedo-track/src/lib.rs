//! The run engine of pedomatch: a recording's objects frame by frame, matched pair by pair,
//! chained into node tracks, with drift correction. One loop runs every run
//! ([`stream_sequence`]), window by window, handing its results as events to a
//! [`SequenceSink`]; a whole run held in memory ([`run_sequence`]) is that loop feeding a
//! [`Collect`]. The second pipeline crate (docs/architecture.md): it reads nothing and writes
//! nothing itself; `pedo-io` gives it recordings and `pedo-output` implements its sinks.
//!
//! This is the job of Tables 1–3 of Tavares & Bastos (2005): for a contour or surface model, the
//! objects of consecutive frames (paired by [`pairing`]) are matched; for the isocontour model,
//! the isobaric contours of one frame are matched level after level (docs/method.md §9). Each
//! matched pair yields one [`PairRow`] with the paper's columns, and the matches are chained into
//! [`Track`]s.
//!
//! | module | stage |
//! |---|---|
//! | [`options`] | [`RunParams`] (what a user sets) resolved into [`SequenceOptions`] (what a run uses) |
//! | `objects` | the objects of every frame: contours, surfaces or isobaric contours |
//! | [`pairing`] | which object of a frame continues which of the frame before (splits, merges) |
//! | `matching` | each pair matched by modal matching (`modal-core`) |
//! | `chain` | matches chained into node tracks |
//! | [`drift`] | drift correction: tracks re-anchored on reference frames |
//! | [`follow`] | material points followed through a stance by anchored registration |
//! | [`inputs`] | the points and regions a user gives to follow ([`RunInputs`]) |
//! | [`result`] | what a run produces: objects, pairs, tracks, counts |
//! | `stream` | the engine: every run, window by window, its events handed to a sink |
//! | [`sink`] | the events of a run ([`SequenceSink`]), gathered whole ([`Collect`]) or replayed |
//! | `run` | a whole run: the engine feeding a [`Collect`] |

#![warn(missing_docs)]

mod chain;
pub mod consistency;
pub mod drift;
pub mod follow;
pub mod inputs;
mod matching;
pub mod moving_regions;
mod objects;
pub mod options;
pub mod pairing;
pub mod result;
mod run;
pub mod sink;
mod stream;
#[cfg(test)]
mod tests;

pub use chain::*;
pub use inputs::{RunInputs, UserInputs};
pub use matching::*;
#[allow(unused_imports)]
pub(crate) use objects::*;
pub use options::*;
pub use result::*;
pub use run::*;
pub use sink::*;
pub use stream::*;
