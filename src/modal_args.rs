//! The options `match`, `run` and `demo` share, read from the one definition of each option in
//! the library crates ([`modal_core::options`], [`pedo_track`], [`pedo_io::units`]):
//! the same names as Python's keywords (`--x-y` for `x_y`), the same words, the same defaults
//! (an absent option is the library's default) and the same help text.

use clap::builder::{PossibleValuesParser, TypedValueParser};
use clap::Args;
use modal_core::options::MatchOverrides;
use modal_core::{
    Choice, ElementKind, MatchParams, Material, Prealign, Refine, Search, ThresholdMode,
};
use pedo_io::units::UnitOverrides;

/// A clap parser for an enumerated option: the possible values are the Rust type's words, the
/// value is parsed by its `FromStr`.
pub fn word<T: Choice + Send + Sync>() -> impl TypedValueParser<Value = T> {
    PossibleValuesParser::new(T::NAMES).try_map(|s| T::parse_word(&s))
}

/// The help text of an option (with its default) from the library's option tables.
pub fn help(name: &str) -> String {
    modal_core::options::match_option_specs()
        .into_iter()
        .chain(modal_core::options::pair_option_specs())
        .chain(pedo_track::recording_option_specs())
        .chain(pedo_output::output_option_specs())
        .find(|s| s.name == name)
        .map(|s| s.help_with_default())
        .unwrap_or_else(|| panic!("option {name} is not in the library's option tables"))
}

/// Every matching option (`pedomatch match`, `run` and `demo`; `pymodal.match` and `run`).
#[derive(Args, Clone, Debug)]
pub struct ModalArgs {
    #[arg(long, value_parser = word::<ElementKind>(), help = help("element"))]
    pub element: Option<ElementKind>,
    #[arg(long, allow_negative_numbers = true, help = help("modes"))]
    pub modes: Option<f64>,
    #[arg(long, value_parser = word::<Search>(), help = help("search"))]
    pub search: Option<Search>,
    #[arg(long, value_parser = word::<assign::Method>(), help = help("solver"))]
    pub solver: Option<assign::Method>,
    #[arg(long, allow_negative_numbers = true, help = help("threshold"))]
    pub threshold: Option<f64>,
    #[arg(long, value_parser = word::<ThresholdMode>(), help = help("threshold_mode"))]
    pub threshold_mode: Option<ThresholdMode>,
    #[arg(long, help = help("excess"))]
    pub no_excess: bool,
    #[arg(long, help = help("paper"))]
    pub paper: bool,
    #[arg(long, value_parser = word::<Prealign>(), help = help("prealign"))]
    pub prealign: Option<Prealign>,
    #[arg(long, allow_negative_numbers = true, value_name = "DEGREES", help = help("max_rotation"))]
    pub max_rotation: Option<f64>,
    #[arg(long, help = help("refits"))]
    pub refits: Option<usize>,
    #[arg(long, allow_negative_numbers = true, help = help("refit_tolerance"))]
    pub refit_tolerance: Option<f64>,
    #[arg(long, value_parser = word::<Refine>(), help = help("refine"))]
    pub refine: Option<Refine>,
    #[arg(long, value_name = "N", help = help("deform_modes"))]
    pub deform_modes: Option<usize>,
    #[arg(long, allow_negative_numbers = true, help = help("deform_stiffness"))]
    pub deform_stiffness: Option<f64>,
    #[arg(long, allow_negative_numbers = true, help = help("kappa"))]
    pub kappa: Option<f64>,
    #[arg(long, value_name = "N", help = help("center_stride"))]
    pub center_stride: Option<usize>,
    #[arg(long, allow_negative_numbers = true, help = help("position_weight"))]
    pub position_weight: Option<f64>,
    #[arg(long, allow_negative_numbers = true, help = help("cost_power"))]
    pub cost_power: Option<f64>,
    #[arg(long, help = help("common_sigma"), conflicts_with = "no_common_sigma")]
    pub common_sigma: bool,
    #[arg(long, help = "Turn --common-sigma off")]
    pub no_common_sigma: bool,
    #[arg(long, help = help("skip_rigid"))]
    pub skip_rigid: bool,
    #[arg(long, help = help("band"))]
    pub band: Option<usize>,
    #[arg(long, value_parser = |s: &str| s.parse::<Material>(), help = help("material"))]
    pub material: Option<Material>,
}

impl ModalArgs {
    /// These options as the library's parameters; absent ones at the library's defaults.
    pub fn params(&self) -> MatchParams {
        MatchOverrides {
            element: self.element,
            modes: self.modes,
            search: self.search,
            solver: self.solver,
            threshold: self.threshold,
            threshold_mode: self.threshold_mode,
            excess: self.no_excess.then_some(false),
            paper: self.paper.then_some(true),
            prealign: self.prealign,
            max_rotation: self.max_rotation,
            refits: self.refits,
            refit_tolerance: self.refit_tolerance,
            refine: self.refine,
            deform_modes: self.deform_modes,
            deform_stiffness: self.deform_stiffness,
            kappa: self.kappa,
            center_stride: self.center_stride,
            position_weight: self.position_weight,
            cost_power: self.cost_power,
            common_sigma: tri_state(self.common_sigma, self.no_common_sigma),
            skip_rigid: self.skip_rigid.then_some(true),
            band: self.band,
            material: self.material,
        }
        .params()
    }
}

/// `--x` / `--no-x` / neither.
pub fn tri_state(on: bool, off: bool) -> Option<bool> {
    match (on, off) {
        (true, _) => Some(true),
        (_, true) => Some(false),
        _ => None,
    }
}

/// The sensor pitch and frame rate overriding a file's.
#[derive(Args, Clone, Debug)]
pub struct UnitArgs {
    #[arg(long, allow_negative_numbers = true, value_name = "X[,Y]", value_parser = |s: &str| pedo_io::units::parse_pitch(s), help = help("pitch_mm"))]
    pub pitch_mm: Option<[f64; 2]>,
    #[arg(long, allow_negative_numbers = true, value_name = "HZ", value_parser = |s: &str| pedo_io::units::parse_frame_rate(s), help = help("frame_rate"))]
    pub frame_rate: Option<f64>,
    #[arg(long, value_name = "UNITS", value_parser = |s: &str| pedo_io::units::parse_units(s), help = help("units"))]
    pub units: Option<String>,
}

impl UnitArgs {
    pub fn overrides(&self) -> UnitOverrides {
        UnitOverrides {
            pitch_mm: self.pitch_mm,
            frame_rate: self.frame_rate,
            units: self.units.clone(),
        }
    }
}

/// How a recording file is read.
#[derive(Args, Clone, Debug, Default)]
pub struct ReadArgs {
    /// Sensor-layout table of a novel pedar insole (CSV lines `insole,sensor,x1,y1,...,x4,y4`,
    /// `# unit: mm` or `cm` for a pitch; default: the bundled layout of the common insole).
    /// Only pedar exports use it.
    #[arg(long, value_name = "FILE")]
    pub layout: Option<std::path::PathBuf>,
}

impl ReadArgs {
    /// Reads the recording at `path` with these settings.
    pub fn read(&self, path: &std::path::Path) -> pedo_io::Result<pedo_io::Recording> {
        pedo_io::formats::read_recording_with(path, &self.options())
    }

    /// These settings as the library's reading options.
    pub fn options(&self) -> pedo_io::formats::ReadOptions {
        pedo_io::formats::ReadOptions {
            layout: self.layout.clone(),
        }
    }
}
