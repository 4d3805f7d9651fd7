//! The folder of `pedomatch register` / `pymodal.register(out=...)`, written whole or not at all
//! ([`OutDir`]): `registered.npz` (the stack of registered images, the masks, the template, the
//! trials' names and maps), `registration.csv` (a row per trial: its map and quality) and
//! `registered.png` (template, mean and SD of the registered peak images) and `register.html`
//! (the same and each trial's difference from the template, with the quality table:
//! [`crate::register_page`]).

use crate::figure::{FigureAxes, RegisteredStackFigure};
use crate::outdir::OutDir;
use crate::register_page::MAX_PAGE_VALUES;
use crate::table::{Cell, Table};
use pedo_io::{IoError, Result};
use pedo_register::{FootImages, StudyRegistration};
use std::path::Path;

/// The files of a register folder.
pub const REGISTER_FILES: [&str; 4] = [
    "registered.npz",
    "registration.csv",
    "registered.png",
    "register.html",
];

/// The columns of `registration.csv`, in order.
pub const REGISTRATION_COLUMNS: [&str; 14] = [
    "trial",
    "fallback",
    "map",
    "m11",
    "m12",
    "tx_sensels",
    "m21",
    "m22",
    "ty_sensels",
    "turn_deg",
    "scale",
    "residual_sensels",
    "mask_xor_pct",
    "correlation",
];

/// The table `registration.csv`: a row per trial, its name first.
pub fn registration_table(names: &[String], reg: &StudyRegistration) -> Table {
    let mut t = Table::new(&REGISTRATION_COLUMNS);
    for (name, r) in names.iter().zip(&reg.trials) {
        let [[m11, m12, tx], [m21, m22, ty]] = r.affine;
        t.rows.push(vec![
            Cell::Text(name.clone()),
            Cell::Int(i64::from(r.fallback)),
            Cell::Text(r.kept.as_str().to_string()),
            Cell::Float(m11, 6),
            Cell::Float(m12, 6),
            Cell::Float(tx, 4),
            Cell::Float(m21, 6),
            Cell::Float(m22, 6),
            Cell::Float(ty, 4),
            Cell::Float(r.turn_deg, 3),
            Cell::Float(r.scale, 5),
            Cell::Float(r.residual_sensels, 4),
            Cell::Float(r.mask_xor_pct, 3),
            Cell::opt(r.correlation, 5),
        ]);
    }
    t
}

/// The per-sensel mean and standard deviation (n − 1; 0 for one trial) of the registered peak
/// images.
pub fn stack_mean_sd(reg: &StudyRegistration) -> (Vec<f64>, Vec<f64>) {
    let len = reg.template.images.peak.len();
    let n = reg.trials.len() as f64;
    let mut mean = vec![0.0; len];
    for r in &reg.trials {
        for (m, v) in mean.iter_mut().zip(&r.images.peak) {
            *m += v / n;
        }
    }
    let mut sd = vec![0.0; len];
    if reg.trials.len() > 1 {
        for r in &reg.trials {
            for ((s, v), m) in sd.iter_mut().zip(&r.images.peak).zip(&mean) {
                *s += (v - m).powi(2) / (n - 1.0);
            }
        }
        sd.iter_mut().for_each(|s| *s = s.sqrt());
    }
    (mean, sd)
}

/// Writes the register folder `out` of `reg`, the trials named `names` (one per trial), its
/// figure drawn with `axes` (the template grid's pitch and the pressure unit).
///
/// # Errors
/// [`IoError::InvalidInput`] when the names do not match the trials; what writing the folder
/// returns ([`OutDir`]).
pub fn write_register_folder(
    out: &Path,
    names: &[String],
    reg: &StudyRegistration,
    axes: &FigureAxes,
) -> Result<()> {
    if names.len() != reg.trials.len() {
        return Err(IoError::invalid(format!(
            "{} names for {} registered trials",
            names.len(),
            reg.trials.len()
        )));
    }
    let dir = OutDir::create(out)?;
    dir.write("registered.npz", &registered_npz(names, reg)?)?;
    dir.write(
        "registration.csv",
        registration_table(names, reg).to_csv().as_bytes(),
    )?;
    let (mean, sd) = stack_mean_sd(reg);
    let tpl = &reg.template.images;
    let png = RegisteredStackFigure {
        rows: tpl.rows,
        cols: tpl.cols,
        template: &tpl.peak,
        mean: &mean,
        sd: &sd,
        trials: reg.trials.len(),
        axes,
    }
    .to_png()?;
    dir.write("registered.png", &png)?;
    let html = crate::register_page::register_page(names, reg, axes, MAX_PAGE_VALUES)?;
    dir.write("register.html", html.as_bytes())?;
    dir.commit()
}

/// One image of a trial's, when it has it.
type Layer = fn(&FootImages) -> Option<&Vec<f64>>;

/// `registered.npz`: `peak`, `pti`, `mean` (trials × rows × columns, float64; `pti` and `mean`
/// when every trial has them), `mask` (bool, same shape), `template_peak` (and `template_pti`,
/// `template_mean` when known), `template_mask`, `trials` (their names), `affine` (trials × 2 × 3).
pub fn registered_npz(names: &[String], reg: &StudyRegistration) -> Result<Vec<u8>> {
    let tpl = &reg.template.images;
    let (rows, cols, n) = (tpl.rows, tpl.cols, reg.trials.len());
    let mut members: Vec<(String, Vec<u8>)> = Vec::new();
    let stack = |get: Layer| -> Option<Vec<f64>> {
        let mut v = Vec::with_capacity(n * rows * cols);
        for r in &reg.trials {
            v.extend_from_slice(get(&r.images)?);
        }
        Some(v)
    };
    let shape3 = format!("({n}, {rows}, {cols})");
    let shape2 = format!("({rows}, {cols})");
    let layers: [(&str, Layer); 3] = [
        ("peak", |f| Some(&f.peak)),
        ("pti", |f| f.pti.as_ref()),
        ("mean", |f| f.mean.as_ref()),
    ];
    for (name, get) in layers {
        if let Some(v) = stack(get) {
            members.push((format!("{name}.npy"), npy_f8(&shape3, &v)));
        }
        if let Some(v) = get(tpl) {
            members.push((format!("template_{name}.npy"), npy_f8(&shape2, v)));
        }
    }
    let masks: Vec<bool> = reg
        .trials
        .iter()
        .flat_map(|r| r.mask.iter().copied())
        .collect();
    members.push(("mask.npy".into(), npy_bool(&shape3, &masks)));
    members.push((
        "template_mask.npy".into(),
        npy_bool(&shape2, &reg.template.mask),
    ));
    members.push(("trials.npy".into(), npy_text(names)));
    let affine: Vec<f64> = reg
        .trials
        .iter()
        .flat_map(|r| r.affine.iter().flatten().copied())
        .collect();
    members.push((
        "affine.npy".into(),
        npy_f8(&format!("({n}, 2, 3)"), &affine),
    ));
    Ok(stored_zip(&members))
}

/// The magic, version 1.0 and header dict, padded to a multiple of 64 bytes.
fn npy_header(descr: &str, shape: &str) -> Vec<u8> {
    let dict = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
    let total = (10 + dict.len() + 1).div_ceil(64) * 64;
    let mut header = dict.into_bytes();
    header.resize(total - 11, b' ');
    header.push(b'\n');
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"\x93NUMPY\x01\x00");
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(&header);
    out
}

fn npy_f8(shape: &str, v: &[f64]) -> Vec<u8> {
    let mut out = npy_header("<f8", shape);
    for x in v {
        out.extend_from_slice(&x.to_le_bytes());
    }
    out
}

fn npy_bool(shape: &str, v: &[bool]) -> Vec<u8> {
    let mut out = npy_header("|b1", shape);
    out.extend(v.iter().map(|&b| u8::from(b)));
    out
}

/// Names as a 1-D array of fixed-width unicode strings (`<U{width}`, UTF-32).
fn npy_text(names: &[String]) -> Vec<u8> {
    let width = names
        .iter()
        .map(|s| s.chars().count())
        .max()
        .unwrap_or(0)
        .max(1);
    let mut out = npy_header(&format!("<U{width}"), &format!("({},)", names.len()));
    for s in names {
        let mut k = 0;
        for c in s.chars() {
            out.extend_from_slice(&(c as u32).to_le_bytes());
            k += 1;
        }
        for _ in k..width {
            out.extend_from_slice(&0u32.to_le_bytes());
        }
    }
    out
}

/// A ZIP archive of `members`, stored (no compression), as `numpy.savez` writes one.
fn stored_zip(members: &[(String, Vec<u8>)]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut central = Vec::new();
    for (name, data) in members {
        let crc = crc32fast::hash(data);
        let offset = out.len() as u32;
        let (size, nlen) = (data.len() as u32, name.len() as u16);
        // Local file header: signature, version 2.0, flags, stored, time, date, crc, sizes.
        out.extend_from_slice(&0x0403_4b50u32.to_le_bytes());
        out.extend_from_slice(&20u16.to_le_bytes());
        out.extend_from_slice(&[0; 4]);
        out.extend_from_slice(&[0, 0, 0x21, 0]);
        out.extend_from_slice(&crc.to_le_bytes());
        out.extend_from_slice(&size.to_le_bytes());
        out.extend_from_slice(&size.to_le_bytes());
        out.extend_from_slice(&nlen.to_le_bytes());
        out.extend_from_slice(&0u16.to_le_bytes());
        out.extend_from_slice(name.as_bytes());
        out.extend_from_slice(data);
        // Central directory entry.
        central.extend_from_slice(&0x0201_4b50u32.to_le_bytes());
        central.extend_from_slice(&20u16.to_le_bytes());
        central.extend_from_slice(&20u16.to_le_bytes());
        central.extend_from_slice(&[0; 4]);
        central.extend_from_slice(&[0, 0, 0x21, 0]);
        central.extend_from_slice(&crc.to_le_bytes());
        central.extend_from_slice(&size.to_le_bytes());
        central.extend_from_slice(&size.to_le_bytes());
        central.extend_from_slice(&nlen.to_le_bytes());
        central.extend_from_slice(&[0; 12]);
        central.extend_from_slice(&offset.to_le_bytes());
        central.extend_from_slice(name.as_bytes());
    }
    let cd_offset = out.len() as u32;
    let cd_size = central.len() as u32;
    out.extend_from_slice(&central);
    out.extend_from_slice(&0x0605_4b50u32.to_le_bytes());
    out.extend_from_slice(&[0; 4]);
    let count = members.len() as u16;
    out.extend_from_slice(&count.to_le_bytes());
    out.extend_from_slice(&count.to_le_bytes());
    out.extend_from_slice(&cd_size.to_le_bytes());
    out.extend_from_slice(&cd_offset.to_le_bytes());
    out.extend_from_slice(&0u16.to_le_bytes());
    out
}
