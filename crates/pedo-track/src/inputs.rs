//! What a user marks on a recording to be followed through the stance by [`crate::follow`]:
//! named points and labelled regions, the run's inputs besides the recording ([`RunInputs`],
//! declared once like every option), read and put in sensels for one recording
//! ([`UserInputs`]).

use modal_core::{OptionError, PathOrRows};
use pedo_io::marks::{given_points_of_rows, read_given_points, GivenPoint, LabelMask};
use pedo_io::recording::Recording;
use pedo_io::{IoError, Result};

modal_core::option_set! {
    /// The points and regions a user gives to be followed through the stance (contour model):
    /// `pedomatch run --points FILE --regions FILE`, `pymodal.run(points=..., regions=...)`.
    /// Held by [`crate::RunParams`]; [`UserInputs::of`] reads them for one recording.
    RunInputs {
        let _d = ();
        /// The points: a CSV file, or rows `x, y` in sensels (Python's `(n, 2)` array).
        points: Option<PathOrRows> = None;
            Value, "none",
            "Points to follow through the stance (contour model): a CSV with a header x,y (sensels; x = column, y = row) or x_mm,y_mm (mm), optional name and frame (0-based) columns; Python also takes an (n, 2) array of x, y in sensels. Each is followed from its frame forwards and backwards through its stance (the contact its object belongs to), written to points.csv with kind user.";
        /// The frame the points are given on, unless the file's `frame` column says.
        points_frame: Option<usize> = None;
            Value, "the first frame whose contact region holds the point",
            "The frame (0-based) the points are given on, for points without a frame column.";
        /// The regions: a mask file, or its rows (Python's 2-D array).
        regions: Option<PathOrRows> = None;
            Value, "none",
            "Regions to follow through the stance (contour model): a mask of the recording's rows x columns (.npy, a CSV grid or an image; Python also takes a 2-D array) of integer labels, 0 = no region; written to regions.csv, each region moving with the foot beside the fixed mask.";
        /// The frame the regions are given on.
        regions_frame: Option<usize> = None;
            Value, "the first frame with an object",
            "The frame (0-based) the regions mask is drawn on.";
    }
}

impl RunInputs {
    /// Nothing to check without a recording ([`UserInputs::of`] reads and checks the inputs).
    pub fn validate(&self) -> std::result::Result<(), OptionError> {
        Ok(())
    }

    /// Whether any point or region is given.
    pub fn any(&self) -> bool {
        self.points.is_some() || self.regions.is_some()
    }
}

/// A point given by the user, in sensels.
#[derive(Debug, Clone, PartialEq)]
pub struct UserPoint {
    /// Its name (the file's `name` column, else `p1`, `p2`, ...).
    pub name: String,
    /// Its position, x = column, y = row, in sensels.
    pub xy: [f64; 2],
    /// The frame it is given on: the file's `frame`, else `points_frame`; `None`: the first
    /// frame whose contact region holds it.
    pub frame: Option<usize>,
}

/// A region given by the user: one label of the mask.
#[derive(Debug, Clone, PartialEq)]
pub struct UserRegion {
    /// Its label in the mask.
    pub label: u32,
    /// Which sensels it holds (row-major, the recording's shape): the fixed region.
    pub cells: Vec<bool>,
    /// Its outline (corners of its sensels' squares, sensels), which is followed.
    pub outline: Vec<[f64; 2]>,
    /// The mask's row length (the recording's columns).
    pub cols: usize,
}

impl UserRegion {
    /// The centres of its sensels (x = column, y = row).
    pub fn centres(&self) -> Vec<[f64; 2]> {
        let cols = self.cols.max(1);
        (self.cells.iter().enumerate())
            .filter(|(_, c)| **c)
            .map(|(i, _)| [(i % cols) as f64, (i / cols) as f64])
            .collect()
    }
}

/// The user's points and regions read for one recording: positions in sensels, the mask of the
/// recording's shape ([`crate::SequenceOptions::inputs`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct UserInputs {
    /// The points, in the order given.
    pub points: Vec<UserPoint>,
    /// The regions, by ascending label.
    pub regions: Vec<UserRegion>,
    /// The frame the regions are drawn on (`None`: the first frame with an object).
    pub regions_frame: Option<usize>,
}

impl UserInputs {
    /// Reads `inputs` for `recording`: the points file (or rows) with millimetres turned into
    /// sensels by the recording's pitch, the mask checked against the recording's shape.
    ///
    /// # Errors
    /// The reading errors of [`pedo_io::regions`]; [`IoError::InvalidInput`] for points in mm
    /// on a recording of unknown pitch, a frame beyond the recording, or a mask of another
    /// shape than the recording's.
    pub fn of(inputs: &RunInputs, recording: &Recording) -> Result<Self> {
        let n = recording.n_frames();
        let check_frame = |f: usize, what: &str| {
            if f >= n {
                Err(IoError::invalid(format!(
                    "{what}: frame {f} is beyond the recording's {} (0-based)",
                    pedo_io::counted(n, "frame")
                )))
            } else {
                Ok(f)
            }
        };
        let mut out = UserInputs::default();
        if let Some(given) = &inputs.points {
            let points = match given {
                PathOrRows::Path(p) => read_given_points(p)?,
                PathOrRows::Rows(rows) => given_points_of_rows(rows)?,
            };
            for GivenPoint {
                name,
                xy,
                mm,
                frame,
            } in points
            {
                let xy = if mm {
                    let p = recording.pitch_mm.ok_or_else(|| {
                        IoError::invalid(format!(
                            "point {name:?} is given in mm (x_mm, y_mm) but the recording's \
                             pitch is unknown: give pitch_mm, or the point in sensels (x, y)"
                        ))
                    })?;
                    [xy[0] / p[0], xy[1] / p[1]]
                } else {
                    xy
                };
                let frame = frame
                    .or(inputs.points_frame)
                    .map(|f| check_frame(f, &format!("point {name:?}")))
                    .transpose()?;
                out.points.push(UserPoint { name, xy, frame });
            }
        }
        if let Some(given) = &inputs.regions {
            let mask = match given {
                PathOrRows::Path(p) => LabelMask::read(p)?,
                PathOrRows::Rows(rows) => LabelMask::of_rows(rows)?,
            };
            let shape = (recording.rows(), recording.cols());
            if mask.shape() != shape {
                return Err(IoError::invalid(format!(
                    "regions: the mask is {} × {} (rows × columns), the recording {} × {}",
                    mask.shape().0,
                    mask.shape().1,
                    shape.0,
                    shape.1
                )));
            }
            out.regions = mask
                .regions()
                .into_iter()
                .map(|label| UserRegion {
                    label,
                    cells: mask.cells(label),
                    outline: mask.outline(label),
                    cols: shape.1,
                })
                .collect();
            out.regions_frame = inputs
                .regions_frame
                .map(|f| check_frame(f, "regions"))
                .transpose()?;
        }
        Ok(out)
    }

    /// Whether there is nothing to follow.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty() && self.regions.is_empty()
    }
}
