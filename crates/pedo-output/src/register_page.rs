//! `register.html`, the page of a register folder: the template, the mean and SD of the
//! registered peak images, each trial's registered image and its difference from the template
//! (a trial at a time, chosen by a slider or its row), and the per-trial quality table of
//! `registration.csv`. Offline and self-contained, as `report.html` is, through the same page
//! maker and script-safe data ([`crate::html_report`]).

use crate::figure::FigureAxes;
use crate::html_report::{facts_html, page};
use crate::register_folder::{registration_table, stack_mean_sd};
use pedo_io::{IoError, Result};
use pedo_register::StudyRegistration;
use serde_json::{json, Value};

/// Values (sensels of the template, mean, SD and the trials' images) the page embeds at most:
/// about 5.5 bytes each in its JSON, so the page stays near 10 MB with plotly.js (4.6 MB;
/// `cargo bench --bench register_page`). A larger stack shows its first trials (the quality
/// table keeps every trial; `registered.npz` holds all).
pub const MAX_PAGE_VALUES: usize = 1_000_000;

const TEMPLATE: &str = include_str!("html/register.html");

/// `register.html` of `reg`, the trials named `names`, drawn with `axes` (the template grid's
/// pitch and the pressure units), embedding at most `max_values` image values.
///
/// # Errors
/// [`IoError::Output`] when the page's data cannot be encoded.
pub fn register_page(
    names: &[String],
    reg: &StudyRegistration,
    axes: &FigureAxes,
    max_values: usize,
) -> Result<String> {
    let data = page_data(names, reg, axes, max_values);
    let shown = data["shown"].as_array().map_or(0, Vec::len);
    let text = serde_json::to_string(&data).map_err(|e| IoError::Output {
        path: "register.html".into(),
        msg: format!("cannot encode the page data: {e}"),
    })?;
    let tpl = &reg.template.images;
    let mut facts = vec![
        ("trials".to_string(), reg.trials.len().to_string()),
        (
            "template grid".to_string(),
            format!("{} rows x {} columns", tpl.rows, tpl.cols),
        ),
        ("pressure units".to_string(), units_text(axes)),
    ];
    if shown < reg.trials.len() {
        facts.push((
            "trials shown".to_string(),
            format!("the first {shown} (the page's size bound; registered.npz holds every trial)"),
        ));
    }
    Ok(page(
        TEMPLATE,
        "registered stack",
        &facts_html(&facts),
        &text,
    ))
}

fn units_text(axes: &FigureAxes) -> String {
    if axes.pressure_units.is_empty() {
        "not stated".into()
    } else {
        axes.pressure_units.clone()
    }
}

/// What the page draws, as JSON: images as flat row-major lists (`null` where not finite), the
/// shown trials' registered peak images, and `registration.csv`'s rows.
fn page_data(
    names: &[String],
    reg: &StudyRegistration,
    axes: &FigureAxes,
    max_values: usize,
) -> Value {
    let tpl = &reg.template.images;
    let len = tpl.peak.len().max(1);
    // The template, mean and SD come first; then as many whole trials as fit (at least one).
    let room = max_values.saturating_sub(3 * len) / len;
    let shown = reg.trials.len().min(room.max(1));
    let (mean, sd) = stack_mean_sd(reg);
    let (pitch, xy_units) = match axes.pitch_mm {
        Some(p) if p.iter().all(|v| v.is_finite() && *v > 0.0) => (p, "mm".to_string()),
        _ => ([1.0, 1.0], axes.data_unit.clone()),
    };
    let trials: Vec<Value> = names
        .iter()
        .zip(&reg.trials)
        .take(shown)
        .map(|(name, r)| json!({ "name": name, "peak": values(&r.images.peak) }))
        .collect();
    json!({
        "rows": tpl.rows,
        "cols": tpl.cols,
        "pitch": pitch,
        "xy_units": xy_units,
        "units": (!axes.pressure_units.is_empty()).then(|| axes.pressure_units.clone()),
        "template": values(&tpl.peak),
        "mean": values(&mean),
        "sd": values(&sd),
        "trials": reg.trials.len(),
        "shown": trials,
        "quality": registration_table(names, reg).to_json(),
    })
}

/// Image values to 6 significant digits (what a colour map and its hover can show), `null`
/// where not finite: a third of the JSON of full precision.
fn values(v: &[f64]) -> Vec<Option<f64>> {
    v.iter()
        .map(|&x| x.is_finite().then(|| significant6(x)))
        .collect()
}

fn significant6(x: f64) -> f64 {
    if x == 0.0 {
        return 0.0;
    }
    // A power of ten multiplies or divides exactly, so the result prints as its 6 digits.
    let k = 5 - x.abs().log10().floor() as i32;
    if k >= 0 {
        let m = 10f64.powi(k.min(300));
        (x * m).round() / m
    } else {
        let m = 10f64.powi(-k);
        (x / m).round() * m
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pedo_register::{FootImages, RegisterParams, TemplateSource};

    /// A rectangle of pressure `top` on a 12 x 8 grid, its rows `r0..r0 + 6`.
    fn foot(r0: usize, top: f64) -> FootImages {
        let (rows, cols) = (12, 8);
        let mut peak = vec![0.0; rows * cols];
        for r in r0..r0 + 6 {
            for c in 2..6 {
                peak[r * cols + c] = top + (r * cols + c) as f64 / 7.0;
            }
        }
        FootImages::from_peak(rows, cols, peak).unwrap()
    }

    fn embedded(html: &str) -> Value {
        let at = html.find("id=\"report-data\">").unwrap() + "id=\"report-data\">".len();
        serde_json::from_str(&html[at..at + html[at..].find("</script>").unwrap()]).unwrap()
    }

    #[test]
    fn the_page_embeds_the_stack_and_keeps_to_its_size_bound() {
        let images = [foot(3, 100.0), foot(4, 120.0), foot(3, 90.0)];
        let source = TemplateSource::Images(foot(3, 100.0));
        let reg =
            pedo_register::register_trials(&images, &source, &RegisterParams::default()).unwrap();
        let names: Vec<String> = ["a </script>", "b", "c"].map(String::from).into();
        let axes = FigureAxes::unscaled("sensels");
        let d = embedded(&register_page(&names, &reg, &axes, MAX_PAGE_VALUES).unwrap());
        assert_eq!(d["trials"], 3);
        assert_eq!(d["shown"].as_array().unwrap().len(), 3);
        assert_eq!(d["shown"][0]["name"], "a </script>");
        assert_eq!(d["quality"].as_array().unwrap().len(), 3);
        let (mean, _) = stack_mean_sd(&reg);
        for (k, r) in reg.trials.iter().enumerate() {
            let shown = d["shown"][k]["peak"].as_array().unwrap();
            for (s, v) in shown.iter().zip(&r.images.peak) {
                assert!((s.as_f64().unwrap() - v).abs() <= 1e-5 * v.abs(), "{s} {v}");
            }
        }
        for (s, v) in d["mean"].as_array().unwrap().iter().zip(&mean) {
            assert!((s.as_f64().unwrap() - v).abs() <= 1e-5 * v.abs(), "{s} {v}");
        }
        // Room for the template, mean, SD and one trial and a half: one trial shown, and said.
        let html = register_page(&names, &reg, &axes, 96 * 4 + 48).unwrap();
        assert_eq!(embedded(&html)["shown"].as_array().unwrap().len(), 1);
        assert!(html.contains("the first 1 (the page"));
    }

    #[test]
    fn values_keep_six_significant_digits() {
        for (x, want) in [
            (123.456_789, 123.457),
            (-0.000_123_456_78, -0.000_123_457),
            (98_765_432.1, 98_765_400.0),
            (0.0, 0.0),
        ] {
            assert_eq!(significant6(x), want);
        }
        assert_eq!(values(&[f64::NAN, 1.0]), vec![None, Some(1.0)]);
    }
}
