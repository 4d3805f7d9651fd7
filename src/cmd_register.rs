//! `pedomatch register`: the footprints of many recordings registered onto one template, for
//! pixel-wise statistics. The work is [`pedo_register`]'s, the folder [`pedo_output`]'s.

use crate::option_args::{OptionArgs, ReadArgs};
use crate::CliError;
use clap::Args;
use pedo_io::counted;
use pedo_register::{FootImages, RegisterParams};
use rayon::prelude::*;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Args)]
pub struct RegisterArgs {
    /// Recordings, one footprint each: files, folders (searched recursively for recordings) or
    /// glob patterns (quoted, e.g. 'data/**/*.csv').
    #[arg(required = true, value_name = "INPUTS")]
    pub inputs: Vec<String>,
    /// The output folder: registered.npz, registration.csv, registered.png and register.html.
    #[arg(long)]
    pub out: PathBuf,
    #[command(flatten)]
    pub register: OptionArgs<RegisterParams>,
    #[command(flatten)]
    pub read: ReadArgs,
    /// Print the per-trial table as JSON on stdout instead of a summary line.
    #[arg(long)]
    pub json: bool,
    /// Print how long reading, registering and writing took on stderr.
    #[arg(long)]
    pub timings: bool,
}

pub fn run(args: RegisterArgs) -> Result<(), CliError> {
    let started = Instant::now();
    let params = args.register.params();
    params.validate()?;
    let paths = pedo_study::find_recordings(&args.inputs)?;
    if paths.is_empty() {
        return Err(CliError::Runtime(format!(
            "no recordings found in {}",
            args.inputs.join(" ")
        )));
    }
    let read = |p: &std::path::Path| -> pedo_io::Result<(FootImages, pedo_io::Recording)> {
        let rec = args.read.read(p)?;
        let images =
            FootImages::of_recording(&rec).map_err(|e| e.of_input(&p.display().to_string()))?;
        Ok((images, rec))
    };
    let trials: Vec<(FootImages, pedo_io::Recording)> = paths
        .par_iter()
        .map(|p| read(p))
        .collect::<pedo_io::Result<_>>()?;
    let read_s = started.elapsed().as_secs_f64();
    let source = params.resolve_template(|p| Ok(read(p)?.0))?;
    // The figure's axes: the template file's or the first trial's pitch, the trials' units.
    use pedo_output::figure::FigureAxes;
    let mut axes = match params.template_source() {
        pedo_register::TemplateName::File(p) => FigureAxes::of_recording(&read(&p)?.1),
        pedo_register::TemplateName::Mun104Left | pedo_register::TemplateName::Mun104Right => {
            FigureAxes::unscaled("sensels")
        }
        _ => FigureAxes::of_recording(&trials[0].1),
    };
    axes.pressure_units = trials[0].1.units.clone();
    let images: Vec<FootImages> = trials.into_iter().map(|t| t.0).collect();
    let t0 = Instant::now();
    let reg = pedo_register::register_trials(&images, &source, &params)?;
    let register_s = t0.elapsed().as_secs_f64();
    let names: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
    let t1 = Instant::now();
    pedo_output::register_folder::write_register_folder(&args.out, &names, &reg, &axes)?;
    let write_s = t1.elapsed().as_secs_f64();
    let table = pedo_output::register_folder::registration_table(&names, &reg);
    if args.json {
        out!("{}", crate::output::pretty(&table.to_json())?);
    } else {
        let fallbacks = reg.trials.iter().filter(|r| r.fallback).count();
        let unmoved = reg
            .trials
            .iter()
            .filter(|r| r.kept == pedo_register::MapKept::Identity)
            .count();
        let mut xor: Vec<f64> = reg.trials.iter().map(|r| r.mask_xor_pct).collect();
        xor.sort_by(f64::total_cmp);
        outln!(
            "{} registered onto a template of {} x {} sensels ({} by the prior's fallback, {} left as they lie: no map overlapped better); median mask XOR {:.1} %; {}",
            counted(reg.trials.len(), "trial"),
            reg.template.images.rows,
            reg.template.images.cols,
            fallbacks,
            unmoved,
            xor[xor.len() / 2],
            args.out.display()
        );
    }
    if args.timings {
        eprintln!(
            "timings: read {read_s:.3} s, register {register_s:.3} s, write {write_s:.3} s, total {:.3} s",
            started.elapsed().as_secs_f64()
        );
    }
    Ok(())
}
