//! The command-line options, made from the one declaration of each option in
//! the library crates ([`modal_core::options`], [`pedo_track`], [`pedo_io::units`],
//! [`pedo_output`]):
//! the same names as Python's keywords (`--x-y` for `x_y`), the same words, the same defaults
//! (an absent option is the library's default) and the same help text.

use clap::builder::{PossibleValuesParser, TypedValueParser};
use modal_core::options::{OptionSpec, OptionText};
use modal_core::{Choice, MatchParams, OptionError, OptionKind, OptionSet};
use pedo_io::formats::ReadOptions;
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
        .chain(pedo_io::formats::read_option_specs())
        .find(|s| s.name == name)
        .map(|s| s.help_with_default())
        .unwrap_or_else(|| panic!("option {name} is not in the library's option tables"))
}

/// The flags of every option of a set declared by `option_set!` ([`OptionSet`]): the matching
/// options ([`MatchParams`]), a run's ([`pedo_track::RunParams`], which holds the matching and
/// unit options), the units ([`UnitOverrides`]) and the outputs
/// ([`pedo_output::OutputOptions`]). The flags are made from the set's specs, so this file names
/// no option; an absent option is the set's default, so defaults are resolved in one step.
///
/// `S` selects which of the set's options a command takes ([`Every`] by default): a command that
/// needs a few options of a set (`inspect`'s noise threshold and units of a run, `match`'s
/// figures and report of a run's outputs) takes them from the same declaration.
#[derive(Clone, Debug, Default)]
pub struct OptionArgs<T, S = Every> {
    params: T,
    selection: std::marker::PhantomData<S>,
}

/// Which options of a set a command takes.
pub trait Selection: Clone + Default + Send + Sync + 'static {
    /// The names of the options taken; `None`: every option of the set.
    const NAMES: Option<&'static [&'static str]>;
    /// Short flags of options taken (`-j` for `--jobs`): the command line's alone.
    const SHORT: &'static [(&'static str, char)] = &[];
}

/// Every option of a set.
#[derive(Clone, Debug, Default)]
pub struct Every;

impl Selection for Every {
    const NAMES: Option<&'static [&'static str]> = None;
}

/// The specs of the options of `T` that `S` selects, in declaration order. A selected name
/// that the set does not declare is a programming error, caught when the command line is built
/// (every command's `--help` is tested).
fn selected_specs<T: OptionSet, S: Selection>() -> Vec<OptionSpec> {
    let specs = T::option_specs();
    let Some(names) = S::NAMES else {
        return specs;
    };
    for name in names {
        assert!(
            specs.iter().any(|s| s.name == *name),
            "option {name} is not declared in the set it is selected from"
        );
    }
    specs
        .into_iter()
        .filter(|s| names.contains(&s.name))
        .collect()
}

/// The matching options of `pedomatch match`.
pub type ModalArgs = OptionArgs<MatchParams>;
/// The unit options of `pedomatch match`.
pub type UnitArgs = OptionArgs<UnitOverrides>;

impl<T: OptionSet, S: Selection> OptionArgs<T, S> {
    /// These options as the library's parameters; absent ones at the library's defaults.
    pub fn params(&self) -> T {
        self.params.clone()
    }
}

/// An option's value checked while the command line is parsed: read as its type asks, then the
/// set's rule (a pitch > 0), so that a bad value is a usage error naming the flag.
fn check_value<T: OptionSet>(name: &'static str, text: OptionText<'_>) -> Result<(), OptionError> {
    let mut params = T::default();
    params.set_option(name, &text)?;
    params.check()
}

impl<T: OptionSet, S: Selection> clap::Args for OptionArgs<T, S> {
    fn augment_args(cmd: clap::Command) -> clap::Command {
        let mut cmd = option_args(cmd, &selected_specs::<T, S>(), check_value::<T>);
        for &(name, short) in S::SHORT {
            cmd = cmd.mut_arg(name, |a| a.short(short));
        }
        cmd
    }
    fn augment_args_for_update(cmd: clap::Command) -> clap::Command {
        Self::augment_args(cmd)
    }
}

impl<T: OptionSet, S: Selection> clap::FromArgMatches for OptionArgs<T, S> {
    fn from_arg_matches(m: &clap::ArgMatches) -> Result<Self, clap::Error> {
        let mut args = Self::default();
        args.update_from_arg_matches(m)?;
        Ok(args)
    }
    fn update_from_arg_matches(&mut self, m: &clap::ArgMatches) -> Result<(), clap::Error> {
        for (name, text) in given_options(m, &selected_specs::<T, S>()) {
            // Checked as it was parsed (`option_args`), so this only stores the value.
            self.params
                .set_option(name, &text)
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
        let value_name = spec.value_name.unwrap_or_else(|| flag(name.to_uppercase()));
        let arg = Arg::new(name)
            .help(spec.help_with_default())
            .value_name(value_name);
        let args = match spec.kind {
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
                let parse = move |s: &str| check(name, OptionText::Text(s)).map(|()| s.to_string());
                // A value with a text form of its own may start with a hyphen (`-50..`);
                // a number may be negative (refused by its rule, not as an unknown flag).
                let arg = match spec.value_name {
                    // A file's name: a following flag is never taken for it.
                    Some("FILE") => arg,
                    Some(_) => arg.allow_hyphen_values(true),
                    None => arg.allow_negative_numbers(true),
                };
                vec![arg.long(long).value_parser(parse)]
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

/// How a recording file is read (`--layout`).
pub type ReadArgs = OptionArgs<ReadOptions>;

impl ReadArgs {
    /// Reads the recording at `path` with these settings.
    pub fn read(&self, path: &std::path::Path) -> pedo_io::Result<pedo_io::Recording> {
        pedo_io::formats::read_recording_with(path, &self.params)
    }
}
