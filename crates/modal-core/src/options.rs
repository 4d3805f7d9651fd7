//! The user-facing matching options: for each one name, one set of values, one default and one
//! meaning, shared by the `pedomatch` command line (`--x-y`) and the Python bindings (`x_y=`).
//!
//! [`MatchParams`] holds what a user chooses; [`MatchParams::to_match_options`] checks every
//! value (the one place where they are validated) and turns them into the engine's
//! [`MatchOptions`] for a kind of input. [`match_option_specs`] describes every option for help
//! texts and for the tests that keep the command line and Python in step. Enumerated values are
//! lower-case words parsed by [`std::str::FromStr`] and printed by [`std::fmt::Display`]; each
//! such type lists its words in [`Choice::NAMES`].

pub use crate::error::OptionError;
use crate::matching::search::ThresholdMode;
use crate::matching::{MatchOptions, Prealign, Refine, Search};
use crate::model::{ElementKind, Material};

impl OptionError {
    /// A word that is not one of `T`'s values.
    pub fn unknown<T: Choice>(value: &str) -> Self {
        Self::new(T::OPTION, value, format!("one of {}", T::NAMES.join(", ")))
    }
}

/// An enumerated option: its values are the lower-case words of [`Choice::NAMES`], parsed by
/// `FromStr` and printed by `Display`.
pub trait Choice: Sized + Copy + std::str::FromStr + std::fmt::Display + 'static {
    /// The option whose values these are, e.g. `"element"`.
    const OPTION: &'static str;
    /// Every accepted word, in the order of the variants.
    const NAMES: &'static [&'static str];

    /// Parses a word, naming the option in the error.
    fn parse_word(s: &str) -> Result<Self, OptionError> {
        s.parse().map_err(|_| OptionError::unknown::<Self>(s))
    }
}

/// Implements [`Choice`], `FromStr` and `Display` for a fieldless enum from `word => Variant`
/// pairs, so that the words are written once.
#[macro_export]
macro_rules! choice {
    ($ty:ty, $option:literal, [$($word:literal => $variant:path),+ $(,)?]) => {
        impl $crate::options::Choice for $ty {
            const OPTION: &'static str = $option;
            const NAMES: &'static [&'static str] = &[$($word),+];
        }
        impl ::std::fmt::Display for $ty {
            fn fmt(&self, f: &mut ::std::fmt::Formatter<'_>) -> ::std::fmt::Result {
                f.write_str(match self { $($variant => $word),+ })
            }
        }
        impl ::std::str::FromStr for $ty {
            type Err = $crate::options::OptionError;
            fn from_str(s: &str) -> ::std::result::Result<Self, Self::Err> {
                match s {
                    $($word => Ok($variant),)+
                    other => Err($crate::options::OptionError::unknown::<$ty>(other)),
                }
            }
        }
        impl $crate::options::OptionField for $ty {
            fn python_type() -> String {
                $crate::options::literal_type(<$ty as $crate::options::Choice>::NAMES)
            }
            fn read<I: $crate::options::OptionInput + ?Sized>(
                input: &I,
                option: &'static str,
            ) -> ::std::result::Result<Self, I::Error> {
                Ok(<$ty as $crate::options::Choice>::parse_word(&input.text(option)?)?)
            }
            fn value(&self) -> $crate::options::OptionValue {
                $crate::options::OptionValue::Word(self.to_string())
            }
        }
    };
}

choice!(ElementKind, "element", ["gaussian" => ElementKind::Gaussian, "axial" => ElementKind::Axial]);
choice!(Search, "search", [
    "global" => Search::Global,
    "local" => Search::Local,
    "best" => Search::Best,
]);
choice!(Prealign, "prealign", [
    "robust" => Prealign::Robust,
    "normalize" => Prealign::Normalize,
    "sensor" => Prealign::Sensor,
]);
choice!(Refine, "refine", [
    "affine" => Refine::Affine,
    "modal" => Refine::Modal,
    "coherent" => Refine::Coherent,
    "auto" => Refine::Auto,
]);
choice!(ThresholdMode, "threshold_mode", [
    "after" => ThresholdMode::AfterAssignment,
    "during" => ThresholdMode::InOptimizer,
]);

impl Choice for assign::Method {
    const OPTION: &'static str = "solver";
    const NAMES: &'static [&'static str] = &assign::Method::NAMES;
}

impl OptionField for assign::Method {
    fn python_type() -> String {
        literal_type(<Self as Choice>::NAMES)
    }
    fn read<I: OptionInput + ?Sized>(input: &I, option: &'static str) -> Result<Self, I::Error> {
        Ok(Self::parse_word(&input.text(option)?)?)
    }
    fn value(&self) -> OptionValue {
        OptionValue::Word(self.to_string())
    }
}

impl std::str::FromStr for Material {
    type Err = OptionError;

    /// A preset name (`rubber`, `steel`, `aluminium`, `cork`, `unit`) or `E,NU,RHO`.
    ///
    /// ```
    /// use modal_core::Material;
    /// assert_eq!("rubber".parse::<Material>().unwrap(), Material::RUBBER);
    /// assert_eq!("2,0.3,5".parse::<Material>().unwrap(), Material::new(2.0, 0.3, 5.0).unwrap());
    /// ```
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let expected = || {
            format!(
                "a preset ({}) or E,NU,RHO with E > 0, -1 < NU < 0.5, RHO > 0",
                Material::PRESETS.join(", ")
            )
        };
        let numbers: Vec<&str> = s.split(',').map(str::trim).collect();
        let material = if numbers.len() == 3 {
            let v: Vec<f64> = numbers
                .iter()
                .map(|x| x.parse::<f64>())
                .collect::<Result<_, _>>()
                .map_err(|_| OptionError::new("material", s, expected()))?;
            Material::new(v[0], v[1], v[2])
        } else {
            Material::preset(s)
        };
        material.map_err(|_| OptionError::new("material", s, expected()))
    }
}

impl std::fmt::Display for Material {
    /// `E,NU,RHO`, the form [`Material`]'s `FromStr` reads back.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{},{},{}", self.young, self.poisson, self.density)
    }
}

/// A value of one option as a front end holds it (a command-line word, a Python object), read as
/// the option's type asks: [`OptionField::read`] calls the one method its type needs, so each
/// front end says once how it reads a number, a count, a switch or a word.
pub trait OptionInput {
    /// What reading fails with: [`OptionError`] on the command line, an exception in Python
    /// (where a value of the wrong type is a `TypeError`, not a `ValueError`).
    type Error: From<OptionError>;
    /// A number.
    fn number(&self, option: &'static str) -> Result<f64, Self::Error>;
    /// A non-negative integer.
    fn count(&self, option: &'static str) -> Result<usize, Self::Error>;
    /// A switch.
    fn switch(&self, option: &'static str) -> Result<bool, Self::Error>;
    /// A word or other text.
    fn text(&self, option: &'static str) -> Result<String, Self::Error>;
    /// A [`Material`]: its text (`rubber`, `E,NU,RHO`) unless a front end has its own form.
    fn material(&self, option: &'static str) -> Result<Material, Self::Error> {
        Ok(self.text(option)?.parse()?)
    }
    /// A file's path: its text unless a front end has its own form (Python's `os.PathLike`).
    /// Only the path: nothing here opens it.
    fn path(&self, option: &'static str) -> Result<std::path::PathBuf, Self::Error> {
        Ok(self.text(option)?.into())
    }
    /// The value as the user wrote it, where a front end holds text (the command line): a type
    /// with a text form of its own (a frame range `10..60`, a pitch `7.62x5.08`) parses it.
    /// `None` where values come typed (Python), read by [`OptionInput::bounds`] and
    /// [`OptionInput::one_or_two`].
    fn written(&self) -> Option<&str> {
        None
    }
    /// Two integer bounds, either open (Python's `(10, None)`); `expected` describes the form in
    /// the error.
    fn bounds(
        &self,
        option: &'static str,
        expected: &str,
    ) -> Result<[Option<isize>; 2], Self::Error>;
    /// One number or a pair of numbers (Python's `5.08` or `(7.62, 5.08)`), as a pair; `expected`
    /// describes the form in the error.
    fn one_or_two(&self, option: &'static str, expected: &str) -> Result<[f64; 2], Self::Error>;
    /// A file's path or the rows of a table of numbers (Python's `(n, 2)` array of points, a
    /// 2-D mask): the text as a path unless a front end has rows to give.
    fn path_or_rows(&self, option: &'static str) -> Result<PathOrRows, Self::Error> {
        Ok(PathOrRows::Path(self.text(option)?))
    }
}

/// The value of an option that names a file or gives its content directly: a path (the command
/// line, Python's `str` or `os.PathLike`) or rows of numbers (Python's array, e.g. `(n, 2)`
/// points or a 2-D mask).
#[derive(Debug, Clone, PartialEq)]
pub enum PathOrRows {
    /// A file's path.
    Path(String),
    /// Rows of numbers, each as given (a front end checks nothing of their lengths).
    Rows(Vec<Vec<f64>>),
}

impl OptionField for PathOrRows {
    fn python_type() -> String {
        "Union[Path, ArrayLike]".into()
    }
    fn value_name() -> Option<&'static str> {
        Some("FILE")
    }
    fn read<I: OptionInput + ?Sized>(input: &I, option: &'static str) -> Result<Self, I::Error> {
        input.path_or_rows(option)
    }
    fn value(&self) -> OptionValue {
        match self {
            PathOrRows::Path(p) => OptionValue::Word(p.clone()),
            PathOrRows::Rows(rows) => OptionValue::Word(format!(
                "an array of {} row{}",
                rows.len(),
                if rows.len() == 1 { "" } else { "s" }
            )),
        }
    }
}

/// The command line's form of an option value: its text (`--modes 0.5`), or a switch given
/// (`--paper` is `Switch(true)`, `--no-excess` is `Switch(false)`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum OptionText<'a> {
    /// The value as written.
    Text(&'a str),
    /// A switch turned on or off.
    Switch(bool),
}

impl OptionText<'_> {
    fn parsed<T: std::str::FromStr>(
        &self,
        option: &'static str,
        expected: &str,
    ) -> Result<T, OptionError> {
        match self {
            OptionText::Text(s) => s
                .trim()
                .parse()
                .map_err(|_| OptionError::new(option, s, expected)),
            OptionText::Switch(b) => Err(OptionError::new(option, b, expected)),
        }
    }
}

impl OptionInput for OptionText<'_> {
    type Error = OptionError;
    fn number(&self, option: &'static str) -> Result<f64, OptionError> {
        self.parsed(option, "a number")
    }
    fn count(&self, option: &'static str) -> Result<usize, OptionError> {
        self.parsed(option, "a non-negative integer")
    }
    fn switch(&self, option: &'static str) -> Result<bool, OptionError> {
        match self {
            OptionText::Switch(b) => Ok(*b),
            OptionText::Text(_) => self.parsed(option, "true or false"),
        }
    }
    fn text(&self, option: &'static str) -> Result<String, OptionError> {
        match self {
            OptionText::Text(s) => Ok(s.to_string()),
            OptionText::Switch(b) => Err(OptionError::new(option, b, "a word")),
        }
    }
    fn written(&self) -> Option<&str> {
        match self {
            OptionText::Text(s) => Some(s),
            OptionText::Switch(_) => None,
        }
    }
    // Text is read by `written`: only a switch reaches these two.
    fn bounds(
        &self,
        option: &'static str,
        expected: &str,
    ) -> Result<[Option<isize>; 2], OptionError> {
        Err(OptionError::new(option, self.as_shown(), expected))
    }
    fn one_or_two(&self, option: &'static str, expected: &str) -> Result<[f64; 2], OptionError> {
        Err(OptionError::new(option, self.as_shown(), expected))
    }
}

impl OptionText<'_> {
    /// The value as an error message shows it.
    fn as_shown(&self) -> String {
        match self {
            OptionText::Text(s) => s.to_string(),
            OptionText::Switch(b) => b.to_string(),
        }
    }
}

/// The type of an option's field: how it is read from an [`OptionInput`], and how Python's type
/// stubs name it.
pub trait OptionField: Sized {
    /// The type in Python's stubs (`float`, `int`, `bool`, `Literal["a", "b"]`, ...).
    fn python_type() -> String;
    /// The value's name in the command line's help (`START..END`) for a type with a text form
    /// of its own, which may start with a hyphen (`-50..`); `None`: the option's name.
    fn value_name() -> Option<&'static str> {
        None
    }
    /// The value of option `option` from `input`.
    fn read<I: OptionInput + ?Sized>(input: &I, option: &'static str) -> Result<Self, I::Error>;
    /// The value as a provenance record states it (`summary.json`, `study.json`).
    fn value(&self) -> OptionValue;
}

impl OptionField for f64 {
    fn python_type() -> String {
        "float".into()
    }
    fn read<I: OptionInput + ?Sized>(input: &I, option: &'static str) -> Result<Self, I::Error> {
        input.number(option)
    }
    fn value(&self) -> OptionValue {
        OptionValue::Float(*self)
    }
}

impl OptionField for usize {
    fn python_type() -> String {
        "int".into()
    }
    fn read<I: OptionInput + ?Sized>(input: &I, option: &'static str) -> Result<Self, I::Error> {
        input.count(option)
    }
    fn value(&self) -> OptionValue {
        OptionValue::Int(*self)
    }
}

impl OptionField for bool {
    fn python_type() -> String {
        "bool".into()
    }
    fn read<I: OptionInput + ?Sized>(input: &I, option: &'static str) -> Result<Self, I::Error> {
        input.switch(option)
    }
    fn value(&self) -> OptionValue {
        OptionValue::Bool(*self)
    }
}

impl OptionField for String {
    fn python_type() -> String {
        "str".into()
    }
    fn read<I: OptionInput + ?Sized>(input: &I, option: &'static str) -> Result<Self, I::Error> {
        input.text(option)
    }
    fn value(&self) -> OptionValue {
        OptionValue::Word(self.clone())
    }
}

/// A file named by the user (a sensor-layout table): read by [`OptionInput::path`], recorded as
/// its text.
impl OptionField for std::path::PathBuf {
    fn python_type() -> String {
        "Path".into()
    }
    fn value_name() -> Option<&'static str> {
        Some("FILE")
    }
    fn read<I: OptionInput + ?Sized>(input: &I, option: &'static str) -> Result<Self, I::Error> {
        input.path(option)
    }
    fn value(&self) -> OptionValue {
        OptionValue::Word(self.display().to_string())
    }
}

impl OptionField for Material {
    fn python_type() -> String {
        "Material".into()
    }
    fn read<I: OptionInput + ?Sized>(input: &I, option: &'static str) -> Result<Self, I::Error> {
        input.material(option)
    }
    fn value(&self) -> OptionValue {
        OptionValue::Word(self.to_string())
    }
}

/// An optional field (`None`: a default that depends on the input) reads as its value.
impl<T: OptionField> OptionField for Option<T> {
    fn python_type() -> String {
        T::python_type()
    }
    fn value_name() -> Option<&'static str> {
        T::value_name()
    }
    fn read<I: OptionInput + ?Sized>(input: &I, option: &'static str) -> Result<Self, I::Error> {
        T::read(input, option).map(Some)
    }
    fn value(&self) -> OptionValue {
        self.as_ref().map_or(OptionValue::Absent, T::value)
    }
}

/// The `python_type` of an enumerated option: `Literal["a", "b"]` of its words.
pub fn literal_type(names: &[&str]) -> String {
    let words: Vec<String> = names.iter().map(|n| format!("\"{n}\"")).collect();
    format!("Literal[{}]", words.join(", "))
}

/// Declares a set of user-facing options once: for each, its field (name, type and default), how
/// it is given on the command line ([`OptionKind`]), its documented default and its meaning. It
/// makes the struct, its [`Default`], `specs()` (the [`OptionSpec`]s every front end, help text,
/// type stub and documentation table is made or checked from) and `set(name, input)`, which
/// reads one option from a front end's [`OptionInput`] by name, and implements [`OptionSet`]
/// (the set must have a `validate(&self) -> Result<(), OptionError>` of its own). A front end
/// thus names no option: it walks the specs.
///
/// A set may hold other sets, declared first (`nested(units: UnitOverrides);`): fields of the
/// struct whose options `set` reads by name too and [`OptionSet::option_specs`] lists after the
/// set's own, so that one value carries every option of a command.
#[macro_export]
macro_rules! option_set {
    (
        $(#[$meta:meta])*
        $name:ident {
            $(nested($($(#[doc = $ndoc:literal])* $nfield:ident: $nty:ty),+ $(,)?);)?
            let $d:ident = $dinit:expr;
            $(
                $(#[doc = $doc:literal])*
                $field:ident: $ty:ty = $default:expr;
                    $kind:expr, $default_text:expr, $help:literal;
            )*
        }
    ) => {
        $(#[$meta])*
        #[derive(Debug, Clone, PartialEq)]
        pub struct $name {
            $($($(#[doc = $ndoc])* pub $nfield: $nty,)+)?
            $($(#[doc = $doc])* pub $field: $ty,)*
        }

        impl Default for $name {
            fn default() -> Self {
                let $d = $dinit;
                Self {
                    $($($nfield: <$nty as Default>::default(),)+)?
                    $($field: $default,)*
                }
            }
        }

        impl $name {
            /// Every option of the set, in field order: its one declaration (not those of the
            /// sets it holds).
            pub fn specs() -> Vec<$crate::options::OptionSpec> {
                #[allow(unused_imports)]
                use $crate::options::OptionKind::*;
                #[allow(unused_variables)]
                let $d = $dinit;
                vec![$(
                    $crate::options::OptionSpec::new(stringify!($field), $kind, $default_text, $help)
                        .with_python_type(<$ty as $crate::options::OptionField>::python_type())
                        .with_value_name(<$ty as $crate::options::OptionField>::value_name()),
                )*]
            }

            /// The value of every option of the set as a provenance record states it
            /// (each field's `OptionField::value`), named and ordered as [`specs`](Self::specs)
            /// (not those of the sets it holds): what a record lists, with the names of the one
            /// declaration.
            pub fn values(&self) -> Vec<(&'static str, $crate::options::OptionValue)> {
                vec![$(
                    (stringify!($field), <$ty as $crate::options::OptionField>::value(&self.$field)),
                )*]
            }

            /// Sets option `name` (of this set or of one it holds) from a front end's `input`
            /// (not validated here); `Ok(false)` when `name` is none of them.
            pub fn set<I: $crate::options::OptionInput + ?Sized>(
                &mut self,
                name: &str,
                input: &I,
            ) -> ::std::result::Result<bool, I::Error> {
                match name {
                    $(stringify!($field) => {
                        self.$field = <$ty as $crate::options::OptionField>::read(input, stringify!($field))?;
                    })*
                    _ => {
                        $($(if self.$nfield.set(name, input)? {
                            return Ok(true);
                        })+)?
                        return Ok(false);
                    }
                }
                Ok(true)
            }
        }

        impl $crate::options::OptionSet for $name {
            fn option_specs() -> Vec<$crate::options::OptionSpec> {
                #[allow(unused_mut)]
                let mut specs = Self::specs();
                $($(specs.extend(<$nty as $crate::options::OptionSet>::option_specs());)+)?
                specs
            }
            fn set_option<I: $crate::options::OptionInput + ?Sized>(
                &mut self,
                name: &str,
                input: &I,
            ) -> ::std::result::Result<bool, I::Error> {
                self.set(name, input)
            }
            fn check(&self) -> ::std::result::Result<(), $crate::options::OptionError> {
                self.validate()
            }
        }
    };
}

/// A set of options declared by [`option_set!`], as a front end walks it: its specs (those of
/// the sets it holds included), a setter by name and its validation.
pub trait OptionSet: Default + Clone + 'static {
    /// Every option the set reads: its own, then those of the sets it holds.
    fn option_specs() -> Vec<OptionSpec>;
    /// Sets option `name` from `input`; `Ok(false)` when the set has no such option.
    fn set_option<I: OptionInput + ?Sized>(
        &mut self,
        name: &str,
        input: &I,
    ) -> Result<bool, I::Error>;
    /// Checks every value.
    fn check(&self) -> Result<(), OptionError>;
}

option_set! {
    /// The matching options a user chooses, with the documented defaults ([`Default`]). A field that
    /// is an `Option` defaults to `None`: the measured recipe's value for the kind of input
    /// (contours and 2-D points, or unordered 3-D points such as brightness surfaces; see
    /// [`MatchOptions::for_input`]).
    ///
    /// ```
    /// use modal_core::{MatchParams, Search};
    /// let params = MatchParams { search: Search::Local, refits: Some(0), ..MatchParams::default() };
    /// let options = params.to_match_options(2, true).unwrap();
    /// assert_eq!((options.search, options.refits), (Search::Local, 0));
    /// assert!(MatchParams { modes: Some(1.5), ..MatchParams::default() }.to_match_options(2, true).is_err());
    /// ```
    MatchParams {
        let d = MatchOptions::default();
        /// Finite element of the modal model.
        element: ElementKind = d.model.element;
            Word(ElementKind::NAMES), d.model.element,
            "Finite element of the modal model: Sclaroff's Gaussian element or bar elements along contour or mesh edges.";
        /// Fraction of the `dim × min(n, m)` modes used as features, in (0, 1] (`None`: the
        /// recipe's).
        modes: Option<f64> = None;
            Value, by_input(|o| o.mode_fraction),
            "Fraction of the dim × min(n, m) vibration modes used as features, in (0, 1].";
        /// Which search produces the matches.
        search: Search = d.search;
            Word(Search::NAMES), d.search,
            "Search: the optimal one-to-one assignment (global), mutual best matches (local), or every node of the first object to its cheapest node of the second (best: many-to-one, no excess step).";
        /// Assignment solver of the global search and of the mode alignment (`ordered`: of the
        /// global search only, on closed contours; `None`: the recipe's, JV, and for a
        /// recording's isocontours [`RUN_ISOCONTOUR_SOLVER`]).
        solver: Option<assign::Method> = None;
            Word(<assign::Method as Choice>::NAMES),
            format!("{} ({RUN_ISOCONTOUR_SOLVER} for a recording's isocontours)", d.method),
            "Assignment solver: Jonker-Volgenant, Kuhn-Munkres or network simplex (same optimum), or ordered: the best assignment whose matches keep the contours' cyclic order (no crossings; closed contours only).";
        /// Reject pairs whose max-normalised cost exceeds this (in [0, 1]); `None` keeps all.
        threshold: Option<f64> = d.threshold;
            Value, "none",
            "Reject pairs whose max-normalised cost exceeds this number in [0, 1]; none keeps all.";
        /// Whether pairs above the threshold are dropped after the assignment or by it.
        threshold_mode: ThresholdMode = d.threshold_mode;
            Word(ThresholdMode::NAMES), d.threshold_mode,
            "Threshold applied after the optimal assignment (after) or by the assignment itself, which may then keep other pairs under it (during).";
        /// Match the nodes the one-to-one search leaves over (global search).
        excess: bool = d.excess;
            NegatedFlag, d.excess,
            "Match the nodes the one-to-one search leaves over (excess-node step, global search).";
        /// Start from the paper's literal setting (centroid and scale pre-alignment, no re-fits).
        paper: bool = false;
            Flag, false,
            "Start from the paper's literal setting: centroid and scale pre-alignment, no affine re-fits.";
        /// Pre-alignment (`None`: robust, or normalize with `paper`; a recording's contours use
        /// [`RUN_PREALIGN`]).
        prealign: Option<Prealign> = None;
            Word(Prealign::NAMES), "robust (normalize with paper; sensor for a recording's contours)",
            "Pre-alignment: rotation search with affine ICP, then for two outlines (outside a run) a point-to-line fit of the outlines (robust), centroid and scale only (normalize), or the sensor coordinates as the prior, moved only by the affine re-fits (sensor: consecutive frames of one recording).";
        /// Largest turn in degrees the robust pre-alignment may find, in (0, 180] (180: any turn;
        /// `None`: the caller's default, unbounded for a pair, [`RUN_MAX_ROTATION`] for a
        /// recording's consecutive frames).
        max_rotation: Option<f64> = None;
            Value, format!("180 (any turn) for a pair, {RUN_MAX_ROTATION} for a recording's consecutive frames"),
            "Largest turn in degrees, in (0, 180], the robust pre-alignment may find between two objects; among turns that fit nearly as well the smallest always wins.";
        /// Maximum modal affine re-fits (`None`: the recipe's; for two closed outlines none after
        /// the rotation search, 2 after another pre-alignment).
        refits: Option<usize> = None;
            Value,
            format!(
                "{} for two closed outlines pre-aligned by the rotation search (match); {} with \
                 another pre-alignment, for 2-D points and for a recording's frames; {} for \
                 unordered 3-D points",
                MatchOptions::for_outlines().refits,
                MatchOptions::default().refits,
                MatchOptions::for_surfaces().refits
            ),
            "Maximum modal affine re-fits (stops earlier when the pairs stop changing).";
        /// Re-fit stopping tolerance in B's node spacings (`None`: the recipe's).
        refit_tolerance: Option<f64> = None;
            Value, by_input(|o| o.refit_tolerance),
            "No further re-fit once every one-to-one pair lies within this fraction of the second object's node spacing of its partner under one affine map; 0 always re-fits.";
        /// What follows the affine re-fits: nothing (`affine`), the modal non-rigid warp
        /// (`modal`), the coherent drift (`coherent`), or for two closed outlines the drift only
        /// when the outline fit leaves them apart (`auto`; `None`: the recipe's, `auto` for two
        /// closed outlines, `affine` otherwise).
        refine: Option<Refine> = None;
            Word(Refine::NAMES),
            format!(
                "{} for two closed outlines (match); {} for points and a recording's frames",
                MatchOptions::for_outlines().refine,
                MatchOptions::default().refine
            ),
            "After the affine re-fits: nothing more (affine); a non-rigid warp of the first object by its own low-order modes, fitted to soft correspondences with the modes' strain energy as regulariser, then one more search (modal; slower, for strongly non-affine deformations); the first object drifted onto the second by a smooth Gaussian-kernel field fitted to soft correspondences (coherent point drift), then assigned on the moved positions, in contour order for two outlines (coherent; for specimens whose proportions differ); or, for two closed outlines pre-aligned by the rotation search, coherent from the centroid-and-scale start when the fitted outlines lie apart or their modal pairs cost a median over 0.15 (two specimens of a shape), and affine otherwise (one outline deformed) (auto).";
        /// Modes of the non-rigid warp, rigid ones included (`refine = modal` only).
        deform_modes: usize = d.deform_modes;
            Value, d.deform_modes,
            "refine=modal: modes of the warp's displacement field, the rigid ones included; at most the rigid count leaves the affine result unchanged.";
        /// Strain-energy weight of the non-rigid warp, > 0 (`refine = modal` only).
        deform_stiffness: f64 = d.deform_stiffness;
            Value, d.deform_stiffness,
            "refine=modal: weight > 0 of the modes' strain energy against the fit; larger keeps the warp closer to the affine alignment.";
        /// Gaussian width factor σ = kappa × mean nearest-neighbour distance (`None`: the recipe's).
        kappa: Option<f64> = None;
            Value, by_input(|o| o.model.kappa),
            "Gaussian width sigma = kappa × mean nearest-neighbour distance.";
        /// Gaussian element: a Gaussian on every `center_stride`-th node only (1: every node;
        /// `None`: the recipe's).
        center_stride: Option<usize> = None;
            Value, by_input(|o| o.model.center_stride),
            "Gaussian element: a Gaussian on every N-th node only (faster, less accurate under severe warps).";
        /// Weight of aligned positions in the cost, in [0, 1] (`None`: the recipe's).
        position_weight: Option<f64> = None;
            Value, by_input(|o| o.position_weight),
            "Weight in [0, 1] of the aligned positions' distance mixed into the modal cost (1: positions only).";
        /// Exponent of the costs the search adds up, > 0 (`None`: the recipe's).
        cost_power: Option<f64> = None;
            Value, by_input(|o| o.cost_power),
            "Exponent > 0 of the costs the search adds up (below 1 favours many near-exact pairs).";
        /// One Gaussian width for both objects (`None`: the recipe's).
        common_sigma: Option<bool> = None;
            TriState,
            format!(
                "{} for two closed outlines (match) and {} for unordered 3-D points; {} for 2-D \
                 points and a recording's frames",
                MatchOptions::for_outlines().common_sigma,
                MatchOptions::for_surfaces().common_sigma,
                MatchOptions::default().common_sigma
            ),
            "One Gaussian width for both objects (for independently sampled point sets).";
        /// Skip the quasi-rigid modes.
        skip_rigid: bool = d.skip_rigid;
            Flag, d.skip_rigid,
            "Leave the quasi-rigid modes out of the features.";
        /// Band of the cross-object mode reordering (0: signs only).
        band: usize = d.band;
            Value, d.band,
            "Band of the cross-object mode reordering (0: signs only).";
        /// Material of the model; only Poisson's ratio changes matches (`None`: the recipe's).
        material: Option<Material> = None;
            Value, by_input(|o| o.model.material),
            "Material: a preset (rubber, steel, aluminium, cork, unit) or E,NU,RHO; only Poisson's ratio changes the matches.";
        /// Most nodes of one object ([`crate::MAX_NODES`]).
        max_nodes: usize = d.max_nodes;
            Value, d.max_nodes,
            "Most nodes an object may have: a larger one is refused before its model, whose dense matrices grow with the square of the nodes, is built (4096 2-D nodes: 512 MiB a matrix).";
    }
}

/// Every matching option of `pedomatch match`, `pedomatch run`, `pymodal.match` and
/// `pymodal.run`, in the order of [`MatchParams`]' fields: its one declaration.
pub fn match_option_specs() -> Vec<OptionSpec> {
    MatchParams::specs()
}

/// `Err` unless `ok`, naming the option, the value and what is expected.
fn check(ok: bool, option: &'static str, value: f64, expected: &str) -> Result<(), OptionError> {
    if ok {
        Ok(())
    } else {
        Err(OptionError::new(option, value, expected))
    }
}

/// The rejection threshold's rule, for the front ends' options and the engine's: costs are
/// max-normalised, so a threshold above 1 would silently keep every pair.
pub(crate) fn check_threshold(t: f64) -> Result<(), OptionError> {
    check(
        (0.0..=1.0).contains(&t),
        "threshold",
        t,
        "a number in [0, 1]",
    )
}

impl MatchParams {
    /// Checks every value.
    pub fn validate(&self) -> Result<(), OptionError> {
        if let Some(m) = self.modes {
            check(m > 0.0 && m <= 1.0, "modes", m, "a fraction in (0, 1]")?;
        }
        if let Some(t) = self.threshold {
            check_threshold(t)?;
        }
        if let Some(r) = self.max_rotation {
            check(
                r > 0.0 && r <= 180.0,
                "max_rotation",
                r,
                "degrees in (0, 180]",
            )?;
        }
        if let Some(t) = self.refit_tolerance {
            check(
                t.is_finite() && t >= 0.0,
                "refit_tolerance",
                t,
                "a finite number >= 0",
            )?;
        }
        check(
            self.deform_stiffness.is_finite() && self.deform_stiffness > 0.0,
            "deform_stiffness",
            self.deform_stiffness,
            "a finite number > 0",
        )?;
        if let Some(k) = self.kappa {
            check(k.is_finite() && k > 0.0, "kappa", k, "a finite number > 0")?;
        }
        if self.max_nodes < 3 {
            return Err(OptionError::new(
                "max_nodes",
                self.max_nodes,
                "an integer >= 3",
            ));
        }
        if self.center_stride == Some(0) {
            return Err(OptionError::new("center_stride", 0, "an integer >= 1"));
        }
        if let Some(w) = self.position_weight {
            check(
                (0.0..=1.0).contains(&w),
                "position_weight",
                w,
                "a number in [0, 1]",
            )?;
        }
        if let Some(p) = self.cost_power {
            check(
                p.is_finite() && p > 0.0,
                "cost_power",
                p,
                "a finite number > 0",
            )?;
        }
        if let Some(m) = self.material {
            m.validate().map_err(|e| match e {
                crate::ModalError::Option(e) => e,
                e => OptionError::new("material", m, e.to_string()),
            })?;
        }
        Ok(())
    }

    /// The engine's options for objects of `dim` dimensions, ordered closed contours or not:
    /// the recipe for that kind of input ([`MatchOptions::for_input`], or
    /// [`MatchOptions::paper`]) with every chosen value applied; two closed outlines given
    /// another `prealign` than the rotation search keep the default recipe's re-fits unless
    /// `refits` is given. `ordered` is left to the caller.
    pub fn to_match_options(&self, dim: usize, ordered: bool) -> Result<MatchOptions, OptionError> {
        let base = if self.paper {
            MatchOptions::paper()
        } else {
            MatchOptions::for_input(dim, ordered)
        };
        let mut o = self.applied_to(base)?;
        if self.refits.is_none() && self.realigns_outlines(dim, ordered) {
            o.refits = MatchOptions::default().refits;
        }
        Ok(o)
    }

    /// `o` with every chosen value applied, once they are checked: for a caller that starts
    /// from a recipe of its own (a recording's frames start from [`MatchOptions::default`], not
    /// from the pair recipe of [`MatchOptions::for_outlines`]). `paper` is the caller's to honour.
    pub fn applied_to(&self, mut o: MatchOptions) -> Result<MatchOptions, OptionError> {
        self.validate()?;
        o.model.element = self.element;
        if let Some(s) = self.center_stride {
            o.model.center_stride = s;
        }
        if let Some(k) = self.kappa {
            o.model.kappa = k;
        }
        if let Some(m) = self.material {
            o.model.material = m;
        }
        o.mode_fraction = self.modes.unwrap_or(o.mode_fraction);
        o.search = self.search;
        o.method = self.solver.unwrap_or(o.method);
        o.threshold = self.threshold;
        o.threshold_mode = self.threshold_mode;
        o.excess = self.excess;
        o.skip_rigid = self.skip_rigid;
        o.band = self.band;
        o.prealign = self.prealign.unwrap_or(o.prealign);
        o.rotation_search.max_rotation = self
            .max_rotation
            .filter(|&r| r < 180.0)
            .or(o.rotation_search.max_rotation);
        o.refits = self.refits.unwrap_or(o.refits);
        o.refit_tolerance = self.refit_tolerance.unwrap_or(o.refit_tolerance);
        o.refine = self.refine.unwrap_or(o.refine);
        o.deform_modes = self.deform_modes;
        o.deform_stiffness = self.deform_stiffness;
        o.max_nodes = self.max_nodes;
        o.position_weight = self.position_weight.unwrap_or(o.position_weight);
        o.cost_power = self.cost_power.unwrap_or(o.cost_power);
        o.common_sigma = self.common_sigma.unwrap_or(o.common_sigma);
        Ok(o)
    }

    /// Whether two closed planar outlines are pre-aligned otherwise than by the outline recipe's
    /// rotation search (not in the paper's setting): the re-fits then do the aligning that the
    /// outline fit would have done, so they default to [`MatchOptions::default`]'s, not to
    /// [`MatchOptions::for_outlines`]' none.
    fn realigns_outlines(&self, dim: usize, ordered: bool) -> bool {
        dim == 2
            && ordered
            && !self.paper
            && self
                .prealign
                .is_some_and(|p| p != MatchOptions::for_outlines().prealign)
    }

    /// Every option as actually used by `used` (the result of
    /// [`MatchParams::to_match_options`]): the recipe's values filled in, in the order of
    /// [`match_option_specs`]. For provenance records.
    pub fn used(&self, used: &MatchOptions) -> Vec<(&'static str, OptionValue)> {
        // The options as the run resolved them, listed by the declaration.
        let resolved = MatchParams {
            element: used.model.element,
            modes: Some(used.mode_fraction),
            search: used.search,
            solver: Some(used.method),
            threshold: used.threshold,
            threshold_mode: used.threshold_mode,
            excess: used.excess,
            paper: self.paper,
            prealign: Some(used.prealign),
            max_rotation: Some(used.rotation_search.max_rotation.unwrap_or(180.0)),
            refits: Some(used.refits),
            refit_tolerance: Some(used.refit_tolerance),
            refine: Some(used.refine),
            deform_modes: used.deform_modes,
            deform_stiffness: used.deform_stiffness,
            kappa: Some(used.model.kappa),
            center_stride: Some(used.model.center_stride),
            position_weight: Some(used.position_weight),
            cost_power: Some(used.cost_power),
            common_sigma: Some(used.common_sigma),
            skip_rigid: used.skip_rigid,
            band: used.band,
            material: Some(used.model.material),
            max_nodes: used.max_nodes,
        };
        // A limit changes no result, only whether there is one: records leave it out, and stay
        // comparable with those made before it was an option (a resumed study's folders).
        let mut values = resolved.values();
        values.retain(|(name, _)| *name != "max_nodes");
        values
    }
}

/// The default [`MatchParams::max_rotation`] of a recording run (`pedomatch run`, `pymodal.run`):
/// consecutive frames hardly turn (a foot rolls over, it does not spin between two frames at
/// 30-500 Hz), while the rotation search's starts lie 10° apart, so the bound keeps the two
/// starts either side of a plausible turn.
pub const RUN_MAX_ROTATION: f64 = 30.0;

/// The default [`MatchParams::prealign`] of a recording run's contours: consecutive frames share
/// the sensor's coordinates, so their placement is the prior (docs/method.md, "Consecutive
/// frames"). Unless `paper` asks for the paper's normalisation.
pub const RUN_PREALIGN: Prealign = Prealign::Sensor;

/// The default [`MatchParams::solver`] of a recording run's isocontours: the level lines of one
/// frame are nested closed contours, so matches between neighbouring levels keep their cyclic
/// order (docs/method.md §6.2, "Order-preserving assignment"; BENCHMARKS.md, "Surfaces and
/// isocontours").
pub const RUN_ISOCONTOUR_SOLVER: assign::Method = assign::Method::Ordered;

/// The value of an option in a provenance record.
#[derive(Debug, Clone, PartialEq)]
pub enum OptionValue {
    /// Not set (e.g. no threshold).
    Absent,
    /// A switch.
    Bool(bool),
    /// A count.
    Int(usize),
    /// A number.
    Float(f64),
    /// An enumerated value or other text.
    Word(String),
    /// Several numbers (a pitch `[x, y]`, a frame range).
    Numbers(Vec<f64>),
}

/// How an option is given on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OptionKind {
    /// A switch that is off by default: `--x` turns it on (Python `x=True`).
    Flag,
    /// A switch that is on by default: `--no-x` turns it off (Python `x=False`).
    NegatedFlag,
    /// A switch whose default depends on the input: `--x` / `--no-x` (Python `True`/`False`).
    TriState,
    /// One of the listed words.
    Word(&'static [&'static str]),
    /// A number or other value written as text.
    Value,
}

/// The description of one option: its name (Python `x_y`, CLI `--x-y`), how it is given, its
/// default and its meaning.
#[derive(Debug, Clone, PartialEq)]
pub struct OptionSpec {
    /// The name, Python style (`x_y`).
    pub name: &'static str,
    /// How it is given.
    pub kind: OptionKind,
    /// The documented default, as text.
    pub default: String,
    /// Its meaning, one sentence for `--help` and docstrings.
    pub help: &'static str,
    /// Its type in Python's stubs (`float`, `int`, `bool`, `Literal["a", "b"]`, ...).
    pub python: String,
    /// The value's name in help texts when it has a text form of its own (`START..END`, which
    /// may start with a hyphen); `None`: the option's name.
    pub value_name: Option<&'static str>,
}

impl OptionSpec {
    /// Builds a description.
    pub fn new(
        name: &'static str,
        kind: OptionKind,
        default: impl ToString,
        help: &'static str,
    ) -> Self {
        let python = match kind {
            OptionKind::Flag | OptionKind::NegatedFlag | OptionKind::TriState => "bool".into(),
            OptionKind::Word(names) => literal_type(names),
            OptionKind::Value => "float".into(),
        };
        Self {
            name,
            kind,
            default: default.to_string(),
            help,
            python,
            value_name: None,
        }
    }

    /// This description with the Python type `python` (an integer option: `int`).
    pub fn with_python_type(mut self, python: impl Into<String>) -> Self {
        self.python = python.into();
        self
    }

    /// This description with the value's own name in help texts ([`OptionField::value_name`]).
    pub fn with_value_name(mut self, value_name: Option<&'static str>) -> Self {
        self.value_name = value_name;
        self
    }

    /// An enumerated option of type `T`, with its default value.
    pub fn choice<T: Choice>(default: T, help: &'static str) -> Self {
        Self::new(T::OPTION, OptionKind::Word(T::NAMES), default, help)
    }

    /// The command-line flags of this option: `--x-y`, `--no-x-y` or both.
    pub fn cli_flags(&self) -> Vec<String> {
        let flag = self.name.replace('_', "-");
        match self.kind {
            OptionKind::NegatedFlag => vec![format!("--no-{flag}")],
            OptionKind::TriState => vec![format!("--{flag}"), format!("--no-{flag}")],
            _ => vec![format!("--{flag}")],
        }
    }

    /// The help text with the default appended, as the command line shows it.
    pub fn help_with_default(&self) -> String {
        match self.kind {
            OptionKind::NegatedFlag => {
                // The help says what the option does when on: "Match the nodes ..." reads
                // "turns off (on by default): match the nodes ...".
                let mut chars = self.help.chars();
                let help = chars
                    .next()
                    .map(|c| c.to_lowercase().chain(chars).collect::<String>())
                    .unwrap_or_default();
                format!("Turns off (on by default): {help}")
            }
            OptionKind::Flag => format!("{} [default: off]", self.help),
            _ => format!("{} [default: {}]", self.help, self.default),
        }
    }
}

/// A recipe-dependent default as text: the contour value and the surface value.
fn by_input<T: std::fmt::Display + PartialEq>(f: impl Fn(&MatchOptions) -> T) -> String {
    let (c, s) = (
        f(&MatchOptions::default()),
        f(&MatchOptions::for_surfaces()),
    );
    if c == s {
        c.to_string()
    } else {
        format!("{c} for contours and 2-D points, {s} for unordered 3-D points")
    }
}

/// Options describing how a pair of objects is read, for `pedomatch match` and `pymodal.match`.
pub fn pair_option_specs() -> Vec<OptionSpec> {
    vec![OptionSpec::new(
        "ordered",
        OptionKind::TriState,
        "decided from the data",
        "Treat both objects as ordered closed contours (enables the order-keeping excess step); by default 2-D points whose consecutive points are nearest neighbours are.",
    )]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn round_trip<T: Choice + PartialEq + std::fmt::Debug>() {
        for &w in T::NAMES {
            let v = T::parse_word(w).unwrap();
            assert_eq!(v.to_string(), w);
        }
        let e = T::parse_word("no-such-word").unwrap_err();
        assert_eq!(e.option, T::OPTION);
        assert!(e.to_string().contains(T::NAMES[0]), "{e}");
    }

    #[test]
    fn a_negated_flag_says_what_it_turns_off_in_one_sentence() {
        let excess = match_option_specs()
            .into_iter()
            .find(|s| s.name == "excess")
            .unwrap();
        assert_eq!(excess.cli_flags(), ["--no-excess"]);
        let help = excess.help_with_default();
        assert!(
            help.starts_with("Turns off (on by default): match the nodes"),
            "{help}"
        );
    }

    #[test]
    fn every_word_parses_and_prints_back() {
        round_trip::<ElementKind>();
        round_trip::<Search>();
        round_trip::<Prealign>();
        round_trip::<ThresholdMode>();
        round_trip::<Refine>();
        round_trip::<assign::Method>();
    }

    #[test]
    fn defaults_are_the_engines_recipe() {
        let d = MatchParams::default();
        assert_eq!(
            d.to_match_options(2, true).unwrap(),
            MatchOptions::for_outlines()
        );
        assert_eq!(
            d.to_match_options(2, false).unwrap(),
            MatchOptions::default()
        );
        assert_eq!(
            d.to_match_options(3, false).unwrap(),
            MatchOptions::for_surfaces()
        );
        let paper = MatchParams { paper: true, ..d };
        assert_eq!(
            paper.to_match_options(2, true).unwrap(),
            MatchOptions::paper()
        );
    }

    #[test]
    fn the_mode_fraction_is_the_recipes_unless_chosen() {
        let fraction = |modes, dim, ordered| {
            let params = MatchParams {
                modes,
                ..MatchParams::default()
            };
            params.to_match_options(dim, ordered).unwrap().mode_fraction
        };
        assert_eq!(fraction(None, 2, true), 0.25);
        assert_eq!(fraction(None, 2, false), 0.25);
        assert_eq!(fraction(None, 3, false), 0.125);
        for (dim, ordered) in [(2, true), (2, false), (3, false)] {
            assert_eq!(fraction(Some(0.3), dim, ordered), 0.3);
        }
    }

    #[test]
    fn outlines_keep_the_refits_unless_the_rotation_search_aligns_them() {
        let refits = |params: MatchParams, dim, ordered| {
            params.to_match_options(dim, ordered).unwrap().refits
        };
        let d = MatchParams::default;
        let (none, some) = (
            MatchOptions::for_outlines().refits,
            MatchOptions::default().refits,
        );
        assert_eq!((none, some), (0, 2));
        assert_eq!(refits(d(), 2, true), none);
        let robust = Some(Prealign::Robust);
        assert_eq!(
            refits(
                MatchParams {
                    prealign: robust,
                    ..d()
                },
                2,
                true
            ),
            none
        );
        for other in [Prealign::Normalize, Prealign::Sensor] {
            let p = MatchParams {
                prealign: Some(other),
                ..d()
            };
            assert_eq!(refits(p.clone(), 2, true), some, "{other}");
            // Only outlines: 2-D point sets keep their re-fits anyway, surfaces have none.
            assert_eq!(refits(p.clone(), 2, false), some);
            assert_eq!(refits(p, 3, false), 0);
        }
        // Chosen values and the paper's setting win.
        let sensor = Some(Prealign::Sensor);
        let chosen = MatchParams {
            prealign: sensor,
            refits: Some(1),
            ..d()
        };
        assert_eq!(refits(chosen, 2, true), 1);
        let paper = MatchParams {
            paper: true,
            prealign: sensor,
            ..d()
        };
        assert_eq!(refits(paper, 2, true), 0);
    }

    #[test]
    fn validation_names_the_option() {
        let d = MatchParams::default;
        let cases: [(MatchParams, &str); 11] = [
            (
                MatchParams {
                    deform_stiffness: 0.0,
                    ..d()
                },
                "deform_stiffness",
            ),
            (
                MatchParams {
                    max_rotation: Some(0.0),
                    ..d()
                },
                "max_rotation",
            ),
            (
                MatchParams {
                    max_rotation: Some(f64::NAN),
                    ..d()
                },
                "max_rotation",
            ),
            (
                MatchParams {
                    modes: Some(0.0),
                    ..d()
                },
                "modes",
            ),
            (
                MatchParams {
                    threshold: Some(f64::NAN),
                    ..d()
                },
                "threshold",
            ),
            (
                MatchParams {
                    threshold: Some(1.5),
                    ..d()
                },
                "threshold",
            ),
            (
                MatchParams {
                    refit_tolerance: Some(-0.5),
                    ..d()
                },
                "refit_tolerance",
            ),
            (
                MatchParams {
                    kappa: Some(0.0),
                    ..d()
                },
                "kappa",
            ),
            (
                MatchParams {
                    center_stride: Some(0),
                    ..d()
                },
                "center_stride",
            ),
            (
                MatchParams {
                    position_weight: Some(1.5),
                    ..d()
                },
                "position_weight",
            ),
            (
                MatchParams {
                    cost_power: Some(f64::INFINITY),
                    ..d()
                },
                "cost_power",
            ),
        ];
        for (p, name) in cases {
            assert_eq!(p.to_match_options(2, true).unwrap_err().option, name);
        }
    }

    #[test]
    fn specs_follow_the_params_and_the_used_record() {
        // max_nodes is a limit, not a setting of the matching: left out of the records, so that
        // the folders of earlier studies still resume.
        let names: Vec<_> = match_option_specs()
            .iter()
            .map(|s| s.name)
            .filter(|&n| n != "max_nodes")
            .collect();
        let d = MatchParams::default();
        let used: Vec<_> = d
            .used(&d.to_match_options(2, true).unwrap())
            .into_iter()
            .map(|(n, _)| n)
            .collect();
        assert_eq!(names, used);
        let excess = &match_option_specs()[6];
        assert_eq!(excess.cli_flags(), ["--no-excess"]);
        let refits = &match_option_specs()[10];
        assert_eq!(refits.name, "refits");
        assert!(refits.default.starts_with("0 for two closed outlines"));
        assert!(refits.default.contains("; 2 with another pre-alignment"));
    }

    #[test]
    fn materials_parse_and_print_back() {
        let m: Material = "1,0.49,1".parse().unwrap();
        assert_eq!(m.to_string().parse::<Material>().unwrap(), m);
        assert_eq!("steel".parse::<Material>().unwrap(), Material::STEEL);
        assert!("jelly".parse::<Material>().is_err());
        assert!("1,0.7,1".parse::<Material>().is_err());
    }
}
