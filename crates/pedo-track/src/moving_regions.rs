//! Anatomical regions that move with the foot (docs/method.md, "Regions carried by the field"):
//! the automatic masks of [`pedo_io::regions`], drawn once over the peak image, carried through
//! each stance by the follower of [`crate::follow`].
//!
//! For each stance the **reference frame** is its frame of largest contact area (the most
//! sensels loaded; the earliest of equals): the foot-flat frame, where the whole sole is down and
//! the peak image's footprint and the frame's contact agree best. On it a region is the mask's
//! sensels that are in contact, so the regions partition that frame's contact. Each connected
//! part of a region (4-neighbours) is followed by its outline (the boundary of its sensels'
//! squares) forwards to the stance's last frame and backwards to its first
//! ([`follow::follow_both_ways`]); on a frame the region is the share of each sensel that
//! one of its parts' followed outlines covers, sensel by sensel. A part that no contour object of the reference frame
//! holds (contact below the contours' smoothing) is not followed.

use crate::follow::{self, FollowParams, Seed, Seeded, REGION_STEP};
use crate::*;
use pedo_io::marks::{polygon_coverage, LabelMask};
use pedo_io::recording::{FootColumns, Recording};
use pedo_io::regions::{RegionMasks, Side};
use pedo_io::stances::Stance;
use pedo_io::{IoError, Result};
use std::collections::BTreeMap;
use std::ops::Range;

/// One anatomical region of one stance, carried by the field.
#[derive(Debug, Clone, PartialEq)]
pub struct MovingRegion {
    /// The stance (0-based, in frame order; a foot's own stances, numbered per foot, for a
    /// recording of both feet apart).
    pub stance: usize,
    /// Its foot, for a recording of both feet apart ([`RegionMasks::sides`]).
    pub foot: Option<Side>,
    /// The region's label in the masks (1-based).
    pub label: u8,
    /// The region's name.
    pub name: String,
    /// The stance's frames, `first..=last`.
    pub frames: (usize, usize),
    /// The frame it is defined on (the stance's frame of largest contact area).
    pub reference_frame: usize,
    /// Its sensels on the reference frame (row-major): the mask's sensels in contact there.
    pub reference_cells: Vec<bool>,
    /// Its connected parts on the reference frame, and of those, the parts followed.
    pub parts: (usize, usize),
    /// Per frame of the stance on which a part was followed: each followed part's outline
    /// there (sensels, x = column, y = row).
    pub outlines: BTreeMap<usize, Vec<Vec<[f64; 2]>>>,
}

impl MovingRegion {
    /// The share of each sensel (`rows × cols`, row-major) it covers on `frame`: the part of
    /// the sensel inside a followed part's outline ([`polygon_coverage`]); `None` on a frame it
    /// was not followed to (outside its stance, or no contour object carried it there).
    pub fn shares(&self, frame: usize, rows: usize, cols: usize) -> Option<Vec<f64>> {
        let parts = self.outlines.get(&frame)?;
        let mut shares = vec![0.0; rows * cols];
        for outline in parts.iter().filter(|o| o.len() >= 3) {
            for (w, part) in shares.iter_mut().zip(polygon_coverage(outline, rows, cols)) {
                *w = (*w + part).min(1.0);
            }
        }
        Some(shares)
    }
}

/// The reference frame of a stance: its frame of largest contact area (sensels of the sensor
/// loaded above 0 and at or above `threshold`), the earliest of equals.
///
/// # Errors
/// A frame the recording does not hold.
pub fn reference_frame(recording: &Recording, stance: &Stance, threshold: f64) -> Result<usize> {
    reference_frame_in(recording, stance, threshold, None)
}

/// [`reference_frame`] counting only the sensels of the columns `columns` (one foot's insole of
/// a recording of both feet apart; every sensel for `None`).
fn reference_frame_in(
    recording: &Recording,
    stance: &Stance,
    threshold: f64,
    columns: Option<&Range<usize>>,
) -> Result<usize> {
    let cols = recording.cols();
    let mut best = (stance.first, 0usize);
    for t in stance.first..=stance.last {
        let n = (contact_cells(recording, t, threshold)?.iter().enumerate())
            .filter(|&(i, &c)| c && columns.is_none_or(|r| r.contains(&(i % cols))))
            .count();
        if n > best.1 {
            best = (t, n);
        }
    }
    Ok(best.0)
}

/// The sensels of the sensor loaded above 0 and at or above `threshold` on frame `t`.
fn contact_cells(recording: &Recording, t: usize, threshold: f64) -> Result<Vec<bool>> {
    let values = recording
        .frame_slice(t)
        .ok_or_else(|| IoError::invalid(format!("frame {t} is not held to follow regions on")))?;
    let mask = recording.sensor_mask();
    Ok(values
        .iter()
        .zip(mask)
        .map(|(&v, &m)| m && v > 0.0 && f64::from(v) >= threshold)
        .collect())
}

/// The connected parts (4-neighbours) of the sensels `cells` (`rows × cols`), each as its
/// sensels' flags.
fn parts_of(cells: &[bool], rows: usize, cols: usize) -> Vec<Vec<bool>> {
    let mut seen = vec![false; cells.len()];
    let mut parts = Vec::new();
    for start in 0..cells.len() {
        if !cells[start] || seen[start] {
            continue;
        }
        let mut part = vec![false; cells.len()];
        let mut stack = vec![start];
        seen[start] = true;
        while let Some(i) = stack.pop() {
            part[i] = true;
            let (r, c) = (i / cols, i % cols);
            let mut near = Vec::with_capacity(4);
            if r > 0 {
                near.push(i - cols);
            }
            if r + 1 < rows {
                near.push(i + cols);
            }
            if c > 0 {
                near.push(i - 1);
            }
            if c + 1 < cols {
                near.push(i + 1);
            }
            for j in near {
                if cells[j] && !seen[j] {
                    seen[j] = true;
                    stack.push(j);
                }
            }
        }
        parts.push(part);
    }
    parts
}

/// The contour objects of a stance's reference frame that may carry its regions, with their
/// outlines (sensels).
struct Holders {
    objects: Vec<usize>,
    outlines: Vec<Vec<[f64; 2]>>,
}

impl Holders {
    /// The object whose outline holds most of the sensel centres of `part` (row-major cells,
    /// `cols` wide; the first on ties), or `None` when none holds any.
    fn holder(&self, part: &[bool], cols: usize) -> Option<usize> {
        let centres: Vec<[f64; 2]> = (part.iter().enumerate())
            .filter(|(_, c)| **c)
            .map(|(i, _)| [(i % cols) as f64, (i / cols) as f64])
            .collect();
        let held = (self.outlines.iter().enumerate())
            .map(|(j, o)| {
                let n = (centres.iter())
                    .filter(|&&c| pedo_io::contour::point_in_polygon(c, o))
                    .count();
                (j, n)
            })
            .max_by_key(|&(j, n)| (n, std::cmp::Reverse(j)));
        held.filter(|&(_, n)| n > 0).map(|(j, _)| self.objects[j])
    }
}

/// Each of `parts` region parts' outline per frame (its points in outline order, where
/// followed) from the followed `points` seeded on them. On a foot (`owned` lists whether each
/// object is of its insole; empty: every object is), a point ends, either way from the
/// `reference` frame, where it would step onto the other insole.
fn part_outlines(
    run: &SequenceResult,
    points: &[follow::FollowedPoint],
    parts: usize,
    owned: &[bool],
    reference: usize,
) -> Vec<BTreeMap<usize, Vec<[f64; 2]>>> {
    let mut by_part: Vec<BTreeMap<usize, Vec<[f64; 2]>>> = vec![BTreeMap::new(); parts];
    let mine = |s: &(usize, [f64; 2])| owned.get(s.0).copied().unwrap_or(true);
    for p in points {
        let Seeded::Region(part) = p.kind else {
            continue;
        };
        let seed = (p.steps.iter())
            .position(|s| run.objects[s.0].frame == reference)
            .unwrap_or(0);
        let lo = p.steps[..seed]
            .iter()
            .rposition(|s| !mine(s))
            .map_or(0, |i| i + 1);
        let hi = (p.steps[seed..].iter())
            .position(|s| !mine(s))
            .map_or(p.steps.len(), |i| seed + i);
        for &(o, xy) in &p.steps[lo..hi.max(lo)] {
            by_part[part]
                .entry(run.objects[o].frame)
                .or_default()
                .push(xy);
        }
    }
    by_part
}

/// The regions of `masks` carried through every stance of `stances` by the objects and pairs
/// of the contour run `run` (see the [module](self)): one [`MovingRegion`] per stance and
/// region, in stance order, then label order. A region with no sensel in contact on its
/// stance's reference frame has no part (it is empty on every frame).
///
/// With `foot` (a foot of a recording of both feet apart, [`Recording::feet`]), only its
/// regions (those of `masks` on its side, [`RegionMasks::sides`]) through its own `stances`, on
/// that foot alone: each stance's reference frame is its frame of most sensels in contact among
/// the foot's columns, and only the contour objects of its insole (those whose centroid lies on
/// its columns, [`SequenceObject::centroid`], [`FootColumns::holds`]) carry its regions, a
/// region's outline ending where the follower would step onto the other insole; its stances
/// are numbered per foot.
///
/// # Errors
/// [`IoError::InvalidInput`] for a run that is not of contours, masks that are not of the
/// recording's shape, or a stance's frame the recording does not hold.
pub fn follow_masks(
    run: &SequenceResult,
    options: &SequenceOptions,
    recording: &Recording,
    masks: &RegionMasks,
    stances: &[Stance],
    threshold: f64,
    foot: Option<&FootColumns>,
) -> Result<Vec<MovingRegion>> {
    if options.model != ObjectModel::Contour {
        return Err(IoError::invalid(
            "regions are carried by the field of contour runs only",
        ));
    }
    let (rows, cols) = (recording.rows(), recording.cols());
    if (masks.rows, masks.cols) != (rows, cols) || masks.labels.len() != rows * cols {
        return Err(IoError::invalid(format!(
            "region masks of {}x{} do not fit frames of {rows}x{cols}",
            masks.rows, masks.cols
        )));
    }
    let aspect = SenselAspect::of(options);
    let params = FollowParams::default();
    let columns = foot.map(|f| &f.columns);
    // Whether each object is of the foot's insole, found once per run (every object for a
    // single footprint: none listed).
    let owned: Vec<bool> = match foot {
        Some(f) => (run.objects.iter())
            .map(|o| !o.shape.is_empty() && f.holds(o.centroid()[0]))
            .collect(),
        None => Vec::new(),
    };
    let mut out = Vec::new();
    for (s, stance) in stances.iter().enumerate() {
        let reference = reference_frame_in(recording, stance, threshold, columns)?;
        let contact = contact_cells(recording, reference, threshold)?;
        let objects: Vec<usize> = (0..run.objects.len())
            .filter(|&o| run.objects[o].frame == reference && run.objects[o].shape.dim() == 2)
            .filter(|&o| owned.get(o).copied().unwrap_or(true))
            .collect();
        let holders = Holders {
            outlines: (objects.iter())
                .map(|&o| follow::outline(&run.objects[o]))
                .collect(),
            objects,
        };
        // Seeds of every part of every region of this stance; `owner[j]` = (region, part).
        let mut seeds = Vec::new();
        let mut owner: Vec<usize> = Vec::new();
        for (k, name) in masks.names.iter().enumerate() {
            let label = (k + 1) as u8;
            if foot.is_some_and(|f| masks.side_of(label) != Some(f.side)) {
                continue;
            }
            let cells: Vec<bool> = (masks.labels.iter().zip(&contact))
                .map(|(&l, &c)| l == label && c)
                .collect();
            let parts = parts_of(&cells, rows, cols);
            let mut followed = 0;
            for part in &parts {
                let Some(object) = holders.holder(part, cols) else {
                    continue;
                };
                let labels: Vec<u32> = part.iter().map(|&c| u32::from(c)).collect();
                let outline = LabelMask::new(rows, cols, labels)?.outline(1);
                let index = owner.len();
                owner.push(out.len());
                seeds.extend(
                    follow::densify(&outline, REGION_STEP)
                        .0
                        .into_iter()
                        .map(|xy| Seed {
                            object,
                            xy,
                            kind: Seeded::Region(index),
                        }),
                );
                followed += 1;
            }
            out.push(MovingRegion {
                stance: s,
                foot: masks.side_of(label),
                label,
                name: name.clone(),
                frames: (stance.first, stance.last),
                reference_frame: reference,
                reference_cells: cells,
                parts: (parts.len(), followed),
                outlines: BTreeMap::new(),
            });
        }
        let followed =
            follow::follow_both_ways(run, aspect, &params, &seeds, stance.first, stance.last)?;
        let by_part = part_outlines(run, &followed.points, owner.len(), &owned, reference);
        for (part, frames) in by_part.into_iter().enumerate() {
            let region = &mut out[owner[part]];
            for (frame, outline) in frames {
                region.outlines.entry(frame).or_default().push(outline);
            }
        }
    }
    Ok(out)
}
