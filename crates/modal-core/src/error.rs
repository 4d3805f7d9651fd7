//! The error type of modal-core: each variant says what was wrong, with the values.
//!
//! The variants fall into four groups ([`ModalError::kind`]): problems of a shape (too few,
//! coincident or collinear nodes, bad connectivity; the same of the matches a correspondence
//! field is fitted to), option values or combinations the method does not accept
//! ([`OptionError`], [`Unsupported`]), inconsistent arguments of the lower-level API (sizes that
//! do not fit), and numerical failures (a matrix that should be positive definite is
//! not, an eigensolver that did not converge).

use std::fmt;

use thiserror::Error;

/// Errors of model building and matching. Every message is one line naming the problem and
/// its values.
///
/// ```
/// use modal_core::{ModalError, Shape, Topology};
/// let e = Shape::from_points_2d(&[[0.0, f64::NAN]], Topology::None).unwrap_err();
/// assert!(matches!(e, ModalError::NonFiniteCoordinate { node: 0, axis: 1, .. }));
/// assert_eq!(e.to_string(), "coordinate 1 of node 0 is not finite (NaN)");
/// ```
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum ModalError {
    // ---- shape problems ------------------------------------------------------------------
    /// The points are neither 2-D nor 3-D.
    #[error("dimension must be 2 or 3, got {dim}")]
    UnsupportedDimension {
        /// The dimension given.
        dim: usize,
    },
    /// The flat coordinate array does not hold whole points.
    #[error("{len} coordinates is not a multiple of the dimension {dim}")]
    CoordinateCount {
        /// Length of the coordinate array.
        len: usize,
        /// The dimension of a point.
        dim: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error("coordinate {axis} of node {node} is not finite ({value})")]
    NonFiniteCoordinate {
        /// The node (0-based).
        node: usize,
        /// The coordinate: 0 for x, 1 for y, 2 for z.
        axis: usize,
        /// The value found.
        value: f64,
    },
    /// The object has fewer nodes than the model or the matching needs.
    #[error("{nodes} nodes; at least {min} are needed")]
    TooFewNodes {
        /// Nodes of the object.
        nodes: usize,
        /// Nodes needed.
        min: usize,
    },
    /// The object has more nodes than a model may have ([`MatchOptions::max_nodes`]): a model
    /// of `n` nodes holds dense matrices of `(dim · n)²` values.
    ///
    /// [`MatchOptions::max_nodes`]: crate::MatchOptions::max_nodes
    #[error(
        "{nodes} nodes are more than the {max} an object may have (its model holds dense \
         matrices of (dim x nodes)^2 values); raise it with --max-nodes (Python max_nodes=)"
    )]
    TooManyNodes {
        /// Nodes of the object.
        nodes: usize,
        /// The most allowed.
        max: usize,
    },
    /// Two nodes are at the same place (an outline that touches itself, duplicated points).
    #[error("nodes {first} and {second} coincide; remove duplicate points")]
    CoincidentNodes {
        /// One of the two nodes.
        first: usize,
        /// The other, at the same place.
        second: usize,
    },
    /// All nodes lie on one line: the object has no extent across it.
    #[error("all nodes are collinear")]
    Collinear,
    /// All nodes are at one place.
    #[error("all nodes coincide (zero spread)")]
    ZeroExtent,
    /// A rigid motion of the nodes is a combination of the others (collinear nodes).
    #[error("rigid motion {motion} is not independent of the others (collinear nodes?)")]
    DependentRigidMotion {
        /// Index of the dependent rigid motion.
        motion: usize,
    },
    /// A bar (axial) model that can move without deforming beyond the rigid motions.
    #[error(
        "the bar model has {zero_modes} zero-energy modes, a {dim}-D body has {expected}: the \
         structure is a mechanism (collinear/coplanar nodes, unconnected nodes or missing bracing)"
    )]
    Mechanism {
        /// Dimension of the body.
        dim: usize,
        /// Zero-energy modes found.
        zero_modes: usize,
        /// Rigid motions of a body of that dimension.
        expected: usize,
    },
    /// An edge joins a node to itself or names a node that does not exist.
    #[error("invalid edge ({}, {}) for {nodes} nodes", .edge[0], .edge[1])]
    InvalidEdge {
        /// The edge's two nodes.
        edge: [usize; 2],
        /// Nodes of the object.
        nodes: usize,
    },
    /// An edge whose two nodes are at the same place.
    #[error("edge ({}, {}) has zero length", .edge[0], .edge[1])]
    ZeroLengthEdge {
        /// The edge's two nodes.
        edge: [usize; 2],
    },
    /// A triangle repeats a vertex or names a node that does not exist.
    #[error("triangle {triangle:?} {}", triangle_problem(.triangle, .nodes))]
    InvalidTriangle {
        /// The triangle's three nodes.
        triangle: [usize; 3],
        /// Nodes of the object.
        nodes: usize,
    },
    /// A triangle of zero area next to a bending hinge.
    #[error("degenerate triangle at edge ({}, {})", .edge[0], .edge[1])]
    DegenerateTriangle {
        /// The hinge edge next to the triangle.
        edge: [usize; 2],
    },
    /// A node that no element holds (a mechanism of its own).
    #[error("node {node} belongs to no element; an unconnected node is a mechanism")]
    UnconnectedNode {
        /// The node (0-based).
        node: usize,
    },
    /// The two objects of a pair have different dimensions.
    #[error("the objects have different dimensions ({a} and {b})")]
    DimensionMismatch {
        /// Dimension of the first object.
        a: usize,
        /// Dimension of the second object.
        b: usize,
    },
    /// An error about one object of a pair.
    #[error("{side}: {error}")]
    Object {
        /// Which object of the pair.
        side: Side,
        /// What is wrong with it.
        error: Box<ModalError>,
    },

    // ---- the matches a correspondence field is fitted to ---------------------------------
    /// Fewer matches than a correspondence field needs.
    #[error("{matches} one-to-one matches; a correspondence field needs at least {min}")]
    TooFewMatches {
        /// One-to-one matches given.
        matches: usize,
        /// Matches needed.
        min: usize,
    },
    /// A node is in two matches, or two matched nodes of one object are at one place.
    #[error("{side}: {}; a field sends each point to one place", coincident_matches(.first, .second))]
    CoincidentMatches {
        /// The object.
        side: Side,
        /// One of the two nodes (0-based, the object's numbering).
        first: usize,
        /// The other (equal to `first` for a node in two matches).
        second: usize,
    },
    /// The matched nodes of one object lie on one line.
    #[error(
        "{side}: the matched nodes are collinear; a plane field needs matches that span an area"
    )]
    CollinearMatches {
        /// The object.
        side: Side,
    },
    /// A match names a node the object does not have.
    #[error("match {pair} names node {node} of {side}, which has {nodes} nodes")]
    MatchOutOfRange {
        /// The match's index among the pairs given.
        pair: usize,
        /// The object.
        side: Side,
        /// The node named.
        node: usize,
        /// Nodes of the object.
        nodes: usize,
    },
    /// A correspondence field of objects that are not 2-D.
    #[error(
        "the correspondence field maps the plane: got {dim}-D objects (fit a brightness \
         surface's nodes by their x and y)"
    )]
    FieldDimension {
        /// The dimension of the objects.
        dim: usize,
    },

    // ---- options -------------------------------------------------------------------------
    /// A user-facing option has a value it does not accept.
    #[error(transparent)]
    Option(#[from] OptionError),
    /// A combination of options and input the method does not support.
    #[error(transparent)]
    Unsupported(#[from] Unsupported),

    // ---- inconsistent arguments of the lower-level API ---------------------------------
    /// A size that does not fit the others (`what` names the quantity).
    #[error("{what}: expected {expected}, found {found}")]
    SizeMismatch {
        /// The quantity.
        what: &'static str,
        /// The size it must have.
        expected: usize,
        /// The size it has.
        found: usize,
    },
    /// More modes were asked for than the model has.
    #[error("{requested} modes requested but only {available} are available")]
    TooFewModes {
        /// Modes asked for.
        requested: usize,
        /// Modes the model has.
        available: usize,
    },
    /// Skipping the rigid modes (or asking for none) leaves no mode to match with.
    #[error("no mode is kept: {skipped} skipped of the {available} available")]
    NoModeKept {
        /// Modes skipped (the rigid ones).
        skipped: usize,
        /// Modes available.
        available: usize,
    },
    /// An entry that must be finite and ≥ 0 is not.
    #[error("{what}: entry {index} is {value}; entries must be finite and >= 0")]
    InvalidEntry {
        /// The array.
        what: &'static str,
        /// The entry's index in it.
        index: usize,
        /// The value found.
        value: f64,
    },

    // ---- numerical failures --------------------------------------------------------------
    /// A matrix that must be symmetric positive definite is not (`pivot`: where Cholesky
    /// stopped, when known).
    #[error(
        "{matrix} is not positive definite{}",
        .pivot.map(|p| format!(" (pivot {p})")).unwrap_or_default()
    )]
    NotPositiveDefinite {
        /// The matrix.
        matrix: &'static str,
        /// Where Cholesky stopped, when known.
        pivot: Option<usize>,
    },
    /// An iterative method did not converge.
    #[error("the {method} did not converge")]
    NotConverged {
        /// The method.
        method: &'static str,
    },
    /// A computation gave zero, infinite or NaN values where it must not.
    #[error("numerical failure in {stage}: zero or non-finite values")]
    NonFiniteResult {
        /// The stage of the computation.
        stage: &'static str,
    },
    /// The Gaussian element's interpolation matrix Γ stays ill-conditioned however small σ.
    #[error("Γ stays ill-conditioned after shrinking σ to {sigma:e}")]
    IllConditioned {
        /// The smallest σ tried.
        sigma: f64,
    },
    /// An internal invariant does not hold: a bug of this crate, not of the input.
    #[error("internal error: {invariant}")]
    Internal {
        /// The invariant that failed.
        invariant: &'static str,
    },

    /// The assignment of nodes or modes failed.
    #[error(transparent)]
    Assign(#[from] assign::AssignError),
}

fn coincident_matches(first: &usize, second: &usize) -> String {
    if first == second {
        format!("node {first} is in two matches")
    } else {
        format!("matched nodes {first} and {second} coincide")
    }
}

fn triangle_problem(t: &[usize; 3], nodes: &usize) -> String {
    if t.iter().any(|v| v >= nodes) {
        format!("refers to a node beyond the {nodes} nodes")
    } else {
        "repeats a vertex".to_string()
    }
}

/// What kind of problem a [`ModalError`] is (bindings map each kind to one exception class).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum ErrorKind {
    /// The object cannot be modelled: too few, coincident or collinear nodes, NaN coordinates,
    /// bad connectivity, objects of different dimensions; too few, coincident or collinear
    /// matches for a correspondence field.
    Shape,
    /// An option's value or a combination of options is not accepted.
    Option,
    /// Arguments of the lower-level API that do not fit together.
    Input,
    /// A numerical method failed.
    Numerical,
    /// The assignment failed ([`assign::AssignError`]).
    Assign,
}

impl ModalError {
    /// The kind of problem (of the wrapped error for [`ModalError::Object`]).
    ///
    /// ```
    /// use modal_core::{ErrorKind, ModalError};
    /// assert_eq!(ModalError::Collinear.kind(), ErrorKind::Shape);
    /// ```
    pub fn kind(&self) -> ErrorKind {
        match self {
            Self::UnsupportedDimension { .. }
            | Self::CoordinateCount { .. }
            | Self::NonFiniteCoordinate { .. }
            | Self::TooFewNodes { .. }
            | Self::TooManyNodes { .. }
            | Self::CoincidentNodes { .. }
            | Self::Collinear
            | Self::ZeroExtent
            | Self::DependentRigidMotion { .. }
            | Self::Mechanism { .. }
            | Self::InvalidEdge { .. }
            | Self::ZeroLengthEdge { .. }
            | Self::InvalidTriangle { .. }
            | Self::DegenerateTriangle { .. }
            | Self::UnconnectedNode { .. }
            | Self::DimensionMismatch { .. }
            | Self::TooFewMatches { .. }
            | Self::CoincidentMatches { .. }
            | Self::CollinearMatches { .. } => ErrorKind::Shape,
            Self::Object { error, .. } => error.kind(),
            Self::Option(_) | Self::Unsupported(_) => ErrorKind::Option,
            Self::SizeMismatch { .. }
            | Self::TooFewModes { .. }
            | Self::NoModeKept { .. }
            | Self::InvalidEntry { .. }
            | Self::MatchOutOfRange { .. }
            | Self::FieldDimension { .. } => ErrorKind::Input,
            Self::NotPositiveDefinite { .. }
            | Self::NotConverged { .. }
            | Self::NonFiniteResult { .. }
            | Self::IllConditioned { .. }
            | Self::Internal { .. } => ErrorKind::Numerical,
            Self::Assign(_) => ErrorKind::Assign,
        }
    }

    /// This error as one about object `side` of a pair ([`ModalError::Object`]).
    ///
    /// ```
    /// use modal_core::{ModalError, Side};
    /// let e = ModalError::TooFewNodes { nodes: 2, min: 3 }.of(Side::B);
    /// assert_eq!(e.to_string(), "object B: 2 nodes; at least 3 are needed");
    /// ```
    pub fn of(self, side: Side) -> Self {
        ModalError::Object {
            side,
            error: Box::new(self),
        }
    }
}

/// Which object of a pair an error is about: A (the first) or B (the second).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// The first object of the pair.
    A,
    /// The second object of the pair.
    B,
}

impl fmt::Display for Side {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Side::A => "object A",
            Side::B => "object B",
        })
    }
}

/// A combination of options and input that the method does not support.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
#[non_exhaustive]
pub enum Unsupported {
    /// The axial (bar) element on points without connectivity.
    #[error("axial elements need connectivity: an ordered closed contour or a triangle mesh")]
    AxialWithoutConnectivity,
    /// The axial element on a 3-D closed contour (a mechanism).
    #[error(
        "axial elements on a 3-D closed contour are a mechanism; give a triangle mesh or use the \
         Gaussian element"
    )]
    Axial3dContour,
    /// Bending hinges on 2-D nodes.
    #[error("bending hinges need 3-D nodes")]
    Hinges2d,
    /// Nodal stiffness and mass matrices of a reduced Gaussian basis.
    #[error("a reduced Gaussian basis (center_stride > 1) has no nodal K and M")]
    ReducedNodalMatrices,
    /// `exact_rigid` with a reduced Gaussian basis.
    #[error(
        "exact_rigid needs the full Gaussian element (center_stride 1): a reduced basis cannot \
         represent the rigid motions exactly"
    )]
    ExactRigidReduced,
    /// `ordered` on triangle meshes.
    #[error("meshes cannot be treated as ordered contours")]
    OrderedMesh,
    /// The order-preserving solver on objects that are not two ordered closed contours.
    #[error(
        "solver = ordered keeps the cyclic order of two closed contours; use jv, hungarian or \
         simplex for surfaces, meshes, point sets and unordered contours"
    )]
    OrderedSolverNeedsContours,
}

/// An option value that is not allowed: which option, the value given, what was expected.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{option} = {value}: expected {expected}")]
pub struct OptionError {
    /// The option's name (Python spelling, `x_y`; the CLI flag is `--x-y`).
    pub option: &'static str,
    /// The rejected value as given.
    pub value: String,
    /// What the option accepts.
    pub expected: String,
}

impl OptionError {
    /// A rejected value of `option`.
    pub fn new(option: &'static str, value: impl ToString, expected: impl Into<String>) -> Self {
        Self {
            option,
            value: value.to_string(),
            expected: expected.into(),
        }
    }
}
