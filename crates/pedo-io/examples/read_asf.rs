//! Reads the bundled Tekscan F-Scan recording (or the file given as the first argument), prints
//! its layout and a few frames' measures, and extracts the contours of its peak frame.
//!
//! Run: `cargo run --example read_asf [-- FILE]`

use pedo_io::{contours, read_recording, ContourOptions, Resample};
use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args_os()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/data/FrasP01L.asf")
        });
    let rec = read_recording(&path)?;
    println!(
        "{}: {} frames of {} x {} sensels, pitch {:?} mm, {:?} s per frame, units {:?}",
        path.file_name().unwrap_or_default().to_string_lossy(),
        rec.n_frames(),
        rec.rows(),
        rec.cols(),
        rec.pitch_mm,
        rec.dt_s,
        rec.units
    );

    let measures = rec.measures(0.0);
    println!("frame  contact sensors  contact area  total force  peak pressure");
    for (f, m) in measures.iter().enumerate().step_by(40) {
        println!(
            "{f:5}  {:15}  {:12.1}  {:11.1}  {:13.1}",
            m.contact_sensors, m.contact_area, m.total_force, m.peak_pressure
        );
    }

    // The frame of largest total force, and its contours resampled every sensel.
    let (peak, _) = measures
        .iter()
        .enumerate()
        .max_by(|x, y| x.1.total_force.total_cmp(&y.1.total_force))
        .ok_or("the recording has no frames")?;
    let options = ContourOptions {
        resample: Resample::Spacing(1.0),
        ..ContourOptions::default()
    };
    let outlines = contours(&rec.frame(peak)?, &options)?;
    println!("frame {peak}: {} contour(s)", outlines.len());
    for c in &outlines {
        let [x, y] = c.centroid();
        println!(
            "  {} points, area {:.1} sensels², centroid ({x:.2}, {y:.2}){}",
            c.points.len(),
            c.area(),
            if c.hole { ", a hole" } else { "" }
        );
    }
    Ok(())
}
