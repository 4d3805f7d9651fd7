//! The command-line options, made from the one declaration of each option in
//! the library crates ([`modal_core::options`], [`pedo_track`], [`pedo_io::units`]):
//! the same names as Python's keywords (`--x-y` for `x_y`), the same words, the same defaults
//! (an absent option is the library's default) and the same help text.

use clap::builder::{PossibleValuesParser, TypedValueParser};
use clap::Args;
use modal_core::options::{OptionSpec, OptionText};
use modal_core::{Choice, MatchParams, OptionError, OptionKind};
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

/// Every matching option (`pedomatch match`, `run` and `demo`; `pymodal.match` and `run`), as
/// the library declares it ([`modal_core::options::match_option_specs`]): the flags are made
/// from that table, so this file names no option.
#[derive(Clone, Debug, Default)]
pub struct ModalArgs {
    params: MatchParams,
}

impl ModalArgs {
    /// These options as the library's parameters; absent ones at the library's defaults.
    pub fn params(&self) -> MatchParams {
        self.params.clone()
    }
}

impl clap::Args for ModalArgs {
    fn augment_args(cmd: clap::Command) -> clap::Command {
        option_args(cmd, &MatchParams::specs(), |name, text| {
            MatchParams::default().set(name, &text).map(drop)
        })
    }
    fn augment_args_for_update(cmd: clap::Command) -> clap::Command {
        Self::augment_args(cmd)
    }
}

impl clap::FromArgMatches for ModalArgs {
    fn from_arg_matches(m: &clap::ArgMatches) -> Result<Self, clap::Error> {
        let mut args = Self::default();
        args.update_from_arg_matches(m)?;
        Ok(args)
    }
    fn update_from_arg_matches(&mut self, m: &clap::ArgMatches) -> Result<(), clap::Error> {
        for (name, text) in given_options(m, &MatchParams::specs()) {
            // Checked as it was parsed (`option_args`), so this only stores the value.
            self.params
                .set(name, &text)
                .map_err(|e| clap::Error::raw(clap::error::ErrorKind::InvalidValue, e))?;
        }
        Ok(())
    }
}

/// Adds a flag to `cmd` for every option of `specs`, from its declaration: `--x-y VALUE` (a word
/// of its list, or a value that `check` reads as the option's type while the command line is
/// parsed), `--x` and `--no-x` for switches, with the declared help and default.
fn option_args(
    mut cmd: clap::Command,
    specs: &[OptionSpec],
    check: fn(&'static str, OptionText<'_>) -> Result<(), OptionError>,
) -> clap::Command {
    use clap::{Arg, ArgAction};
    // clap keeps 'static names; the flags are made once per process.
    let flag = |s: String| -> &'static str { Box::leak(s.into_boxed_str()) };
    for spec in specs {
        let name = spec.name;
        let long = flag(name.replace('_', "-"));
        let arg = Arg::new(name)
            .help(spec.help_with_default())
            .value_name(flag(name.to_uppercase()));
        let args =
            match spec.kind {
                OptionKind::Flag => vec![arg.long(long).action(ArgAction::SetTrue)],
                OptionKind::NegatedFlag => {
                    vec![arg
                        .long(flag(format!("no-{long}")))
                        .action(ArgAction::SetTrue)]
                }
                OptionKind::TriState => vec![
                    arg.long(long).action(ArgAction::SetTrue),
                    Arg::new(flag(format!("no_{name}")))
                        .long(flag(format!("no-{long}")))
                        .action(ArgAction::SetTrue)
                        .help(format!("Turn --{long} off"))
                        .conflicts_with(name),
                ],
                OptionKind::Word(words) => {
                    vec![arg
                        .long(long)
                        .value_parser(PossibleValuesParser::new(words))]
                }
                OptionKind::Value => {
                    vec![arg.long(long).allow_negative_numbers(true).value_parser(
                        move |s: &str| check(name, OptionText::Text(s)).map(|()| s.to_string()),
                    )]
                }
            };
        cmd = cmd.args(args);
    }
    cmd
}

/// The options of `specs` given on the command line `m`, in declaration order, as the library
/// reads them: a value's text, or a switch turned on or off.
fn given_options<'m>(
    m: &'m clap::ArgMatches,
    specs: &[OptionSpec],
) -> Vec<(&'static str, OptionText<'m>)> {
    let on = |id: &str| m.get_flag(id);
    let mut given = Vec::new();
    for spec in specs {
        let name = spec.name;
        let value = match spec.kind {
            OptionKind::Flag => on(name).then_some(OptionText::Switch(true)),
            OptionKind::NegatedFlag => on(name).then_some(OptionText::Switch(false)),
            OptionKind::TriState => {
                tri_state(on(name), on(&format!("no_{name}"))).map(OptionText::Switch)
            }
            OptionKind::Word(_) | OptionKind::Value => m
                .get_one::<String>(name)
                .map(|s| OptionText::Text(s.as_str())),
        };
        given.extend(value.map(|v| (name, v)));
    }
    given
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
