//! `pedomatch inspect FILE`: what a recording holds, in its physical units.

use crate::option_args::{OptionArgs, Selection};
use crate::CliError;
use clap::Args;
use pedo_output::{describe, InputInfo};
use std::path::PathBuf;

#[derive(Args)]
pub struct InspectArgs {
    /// The recording: Tekscan .asf or CSV export, emed .lst, pedar .asc, Zebris .apd or raw-data
    /// XML/JSON, footscan export, .npy/.npz, a CSV grid, a PNG/TIFF image, a folder of images or a
    /// numbered pattern (`walk_%03d.png`); the format is detected from the content.
    pub recording: PathBuf,
    #[command(flatten)]
    pub read: crate::option_args::ReadArgs,
    /// The options of a run that say how a recording's values read: its noise threshold and
    /// units.
    #[command(flatten)]
    pub options: OptionArgs<pedo_track::RunParams, Reading>,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

/// The options of `pedo_track::RunParams` that `inspect` takes: those that say how a recording's
/// values read, as a run reads them.
#[derive(Clone, Debug, Default)]
pub struct Reading;

impl Selection for Reading {
    const NAMES: Option<&'static [&'static str]> = Some(&[
        "noise",
        "pitch_mm",
        "frame_rate",
        "units",
        "time_axis",
        "clip_negative",
    ]);
}

pub fn run(args: InspectArgs) -> Result<(), CliError> {
    let mut rec = args.read.read(&args.recording)?;
    let params = args.options.params();
    params
        .units
        .apply(&mut rec)
        .map_err(|e| e.of_input(&args.recording.display().to_string()))?;
    let input = InputInfo::of_path(&args.recording)?;
    let threshold = params.noise_threshold(&rec);
    let d = describe(&rec, &input, threshold);
    if args.json {
        outln!("{}", crate::output::pretty(&d)?);
        return Ok(());
    }
    fn show(v: &serde_json::Value) -> String {
        match v {
            serde_json::Value::Null => "unknown".to_string(),
            serde_json::Value::String(s) => s.clone(),
            // Six decimals hide binary rounding (0.032 s × 205 frames = 6.5600000000000005 s).
            serde_json::Value::Number(n) if n.is_f64() => {
                let x = n.as_f64().unwrap_or(f64::NAN);
                ((x * 1e6).round() / 1e6).to_string()
            }
            // A pitch: "5.08 x 5.08" (columns x rows), as the grid line writes its sizes.
            serde_json::Value::Array(items) => {
                items.iter().map(show).collect::<Vec<_>>().join(" x ")
            }
            other => other.to_string(),
        }
    }
    outln!("file            {}", args.recording.display());
    outln!("sha256          {}", show(&d["sha256"]));
    outln!("format          {}", show(&d["format"]));
    outln!("frames          {}", d["frames"]);
    outln!(
        "grid            {} rows x {} cols, {} sensors",
        d["rows"],
        d["cols"],
        d["sensors"]
    );
    outln!("pitch (mm)      {}", show(&d["pitch_mm"]));
    outln!("frame rate (Hz) {}", show(&d["frame_rate_hz"]));
    outln!("duration (s)    {}", show(&d["duration_s"]));
    outln!("pressure units  {}", show(&d["pressure_units"]));
    outln!("noise threshold {}", show(&d["noise_threshold"]));
    let negatives = &d["negative_values"];
    outln!(
        "negative values {}",
        match negatives["count"].as_u64() {
            Some(0) | None => "none".to_string(),
            Some(n) => format!(
                "{n} (min {}){}",
                show(&negatives["min"]),
                if negatives["clipped"].as_bool() == Some(true) {
                    ", clipped to 0 (--clip-negative)"
                } else {
                    "; --clip-negative sets them to 0"
                }
            ),
        }
    );
    outln!(
        "streams         {}",
        match d["read_whole"].as_str() {
            None => "yes: a run with tables only reads its frames as it goes".to_string(),
            Some(why) => format!("no: {why}"),
        }
    );
    outln!(
        "per-frame measures over all {} frames ({} with contact), values of at least {threshold}:",
        d["frames"],
        d["loaded_frames"]
    );
    if let Some(m) = d["measures"].as_object() {
        for (name, s) in m {
            let f = |k: &str| s[k].as_f64().map_or("-".into(), |v| format!("{v:.3}"));
            outln!(
                "  {name:<22} min {}  mean {}  max {}",
                f("min"),
                f("mean"),
                f("max")
            );
        }
    }
    Ok(())
}
