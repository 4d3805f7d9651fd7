//! Zebris FDM frame-by-frame raw-data export, as XML (written by the Zebris FDM software) or as
//! the gzip-compressed JSON the public TRIPOD dataset converts it to.
//!
//! The structure, as read by the public TRIPOD pipeline (Trautmann et al., *Data* 6(9) 95, 2021;
//! repository `HPI-CH/TRIPOD`, `src/preprocessing/convert_zebris.py`, MIT):
//!
//! ```text
//! <measurement>
//!   <cell_count><x>X</x><y>Y</y></cell_count>            whole plate, in sensors
//!   <movements><movement><clips>
//!     <clip>                                             the pressure clip
//!       <cell_size><x>8.467</x><y>8.467</y></cell_size>  sensor pitch, mm
//!       <frequency>100</frequency>                       frames per second
//!       <units>N/cm2</units> <count>K</count> <begin>0.0</begin>
//!       <data>
//!         <quant>                                        one frame
//!           <cell_begin><x>bx</x><y>by</y></cell_begin>  window of loaded sensors
//!           <cell_count><x>w</x><y>h</y></cell_count>
//!           <cells>v v v …</cells>                       w × h values, x fastest
//!         </quant>
//!         <quant/>                                       an unloaded frame
//!   …   <clip> (treadmill velocity, one value per quant) </clip>
//! ```
//!
//! The JSON form holds the same fields flattened: `cell_count`, `cell_size`, `frequency`,
//! `pressure_unit`, `sample_count`, `begin`, and `samples` with `origin`, `size`, `pressure`.
//!
//! Each frame is the whole plate (`Y` rows × `X` columns). Zebris' y axis points forwards (up
//! the plate), so row 0 of a frame is the plate's far end (`y = Y − 1`): the image reads as the
//! plate seen from above with the walking direction up. Every sensor of the plate exists.

use super::parse_num;
use crate::error::{IoError, Result};
use crate::recording::stated_units;
use crate::recording::{Format, Recording};
use quick_xml::events::Event;
use quick_xml::Reader;

/// Plates larger than this many sensors are refused before anything is allocated: the largest
/// Zebris platforms and treadmills hold about 12,000, and every frame costs the whole plate.
const MAX_PLATE_SENSORS: usize = 1 << 16;

/// What the header states, as read.
#[derive(Default, Debug)]
struct Header {
    plate: [Option<usize>; 2],
    cell_size: [Option<f64>; 2],
    frequency: Option<f64>,
    units: Option<String>,
    count: Option<usize>,
}

/// One frame's window: `origin` and `size` as `[x, y]`, values x fastest.
#[derive(Default, Debug)]
struct Window {
    origin: [Option<usize>; 2],
    size: [Option<usize>; 2],
    cells: Option<String>,
}

/// One frame as read: its window (`origin`, `size` as `[x, y]`) and values x fastest; `None` for
/// an unloaded frame. Frames stay sparse until the recording is built.
type Sparse = Option<([usize; 2], [usize; 2], Vec<f32>)>;

/// The frames of one clip as they are read.
struct Frames<'a> {
    name: &'a str,
    cols: usize,
    rows: usize,
    frames: Vec<Sparse>,
}

impl<'a> Frames<'a> {
    fn new(name: &'a str, plate: [Option<usize>; 2]) -> Result<Self> {
        let [Some(cols), Some(rows)] = plate else {
            return Err(IoError::format(
                name,
                "a frame before the plate's <cell_count> (x and y)",
            ));
        };
        if cols == 0 || rows == 0 || cols.saturating_mul(rows) > MAX_PLATE_SENSORS {
            return Err(IoError::format(
                name,
                format!("a plate of {cols} x {rows} sensors is not a pressure plate"),
            ));
        }
        Ok(Frames {
            name,
            cols,
            rows,
            frames: Vec::new(),
        })
    }

    /// Adds one frame (`values` x fastest in the window of `size` at `origin`).
    fn push(&mut self, origin: [usize; 2], size: [usize; 2], values: &[f64]) -> Result<()> {
        let k = self.frames.len();
        let err = |msg: String| IoError::format(self.name, format!("frame {k}: {msg}"));
        let [w, h] = size;
        if origin[0].saturating_add(w) > self.cols || origin[1].saturating_add(h) > self.rows {
            return Err(err(format!(
                "the window at ({}, {}) of {w} x {h} sensors leaves the {} x {} plate",
                origin[0], origin[1], self.cols, self.rows
            )));
        }
        if values.len() != w * h {
            return Err(err(format!(
                "{} values for a window of {w} x {h} = {} sensors",
                values.len(),
                w * h
            )));
        }
        if let Some(i) = values.iter().position(|v| *v < 0.0) {
            return Err(err(format!("value {i} is negative ({})", values[i])));
        }
        if w == 0 || h == 0 {
            self.frames.push(None);
            return Ok(());
        }
        let v = values.iter().map(|&x| x as f32).collect();
        self.frames.push(Some((origin, size, v)));
        Ok(())
    }

    fn push_empty(&mut self) {
        self.frames.push(None);
    }

    fn n(&self) -> usize {
        self.frames.len()
    }

    /// The dense recording: every frame the whole plate, row 0 at the plate's far end.
    fn finish(self, h: &Header) -> Result<Recording> {
        let n = self.frames.len();
        if let Some(stated) = h.count
            && stated != n
        {
            return Err(IoError::format(
                self.name,
                format!(
                    "truncated or inconsistent: the pressure clip holds {n} frames, its \
                         <count> states {stated}"
                ),
            ));
        }
        if n == 0 {
            return Err(IoError::format(self.name, "no frames in the pressure clip"));
        }
        let per = self.rows * self.cols;
        let mut data = vec![
            0.0f32;
            n.checked_mul(per).ok_or_else(|| {
                IoError::format(self.name, format!("{n} frames of {per} sensors overflow"))
            })?
        ];
        for (frame, sparse) in data.chunks_mut(per).zip(&self.frames) {
            let Some((origin, [w, _], values)) = sparse else {
                continue;
            };
            for (j, line) in values.chunks(*w).enumerate() {
                let row = self.rows - 1 - (origin[1] + j);
                frame[row * self.cols + origin[0]..][..*w].copy_from_slice(line);
            }
        }
        let mask = vec![true; per];
        let mut rec = Recording::new(n, self.rows, self.cols, data, mask)?;
        if let [Some(dx), Some(dy)] = h.cell_size
            && dx > 0.0
            && dy > 0.0
        {
            rec.pitch_mm = Some([dx, dy]);
        }
        rec.dt_s = h.frequency.filter(|f| *f > 0.0).map(|f| 1.0 / f);
        rec.units = stated_units(h.units.as_deref().unwrap_or_default());
        Ok(rec)
    }
}

fn values(text: &str) -> std::result::Result<Vec<f64>, String> {
    text.split_ascii_whitespace()
        .enumerate()
        .map(|(i, t)| parse_num(t).ok_or_else(|| format!("value {i} is not a number: {t:?}")))
        .collect()
}

fn count(text: &str, what: &str) -> std::result::Result<usize, String> {
    text.trim()
        .parse::<usize>()
        .map_err(|_| format!("{what} is not a count: {:?}", text.trim()))
}

/// 1-based line of a byte offset.
fn line_of(bytes: &[u8], pos: u64) -> usize {
    let end = (pos as usize).min(bytes.len());
    1 + bytes[..end].iter().filter(|&&b| b == b'\n').count()
}

/// One `<clip>` as read: its header, its frames, and whether it is a pressure clip (it has a
/// `<cell_size>` or frames with windows); the other clips (treadmill velocity) are dropped.
struct Clip<'a> {
    header: Header,
    frames: Option<Frames<'a>>,
    window: Window,
    is_pressure: bool,
}

/// Parses the XML raw-data export held in memory; `name` appears in error messages.
pub fn parse_zebris_xml(bytes: &[u8], name: &str) -> Result<Recording> {
    let mut reader = Reader::from_reader(bytes);
    let mut path: Vec<String> = Vec::new();
    let mut text = String::new();
    let mut plate: [Option<usize>; 2] = [None, None];
    let mut clip: Option<Clip> = None;
    let mut pressure: Option<(Frames, Header)> = None;
    let mut buf = Vec::new();
    loop {
        let pos = reader.buffer_position();
        let line = || line_of(bytes, pos);
        let event = reader.read_event_into(&mut buf).map_err(|e| {
            IoError::parse(
                name,
                line_of(bytes, reader.error_position()),
                format!("malformed or truncated XML: {e}"),
            )
        })?;
        match event {
            Event::Start(e) => {
                let tag = e.local_name().as_ref().to_string();
                if tag == "clip" {
                    clip = Some(Clip {
                        header: Header::default(),
                        frames: None,
                        window: Window::default(),
                        is_pressure: false,
                    });
                } else if tag == "quant"
                    && let Some(c) = clip.as_mut()
                {
                    c.window = Window::default();
                }
                path.push(tag);
                text.clear();
            }
            Event::Empty(e) => {
                if let ("quant", Some(c)) = (e.local_name().as_ref(), clip.as_mut()) {
                    frames_of(&mut c.frames, name, plate)?.push_empty();
                }
            }
            Event::Text(t) => text.push_str(&t),
            Event::CData(t) => text.push_str(&t),
            Event::GeneralRef(r) => text.push_str(&resolve_ref(&r)),
            Event::End(_) => {
                let Some(tag) = path.pop() else {
                    return Err(IoError::parse(
                        name,
                        line(),
                        "a closing tag without an opening one",
                    ));
                };
                let parent: Vec<&str> = path.iter().map(String::as_str).collect();
                let fail = |msg: String| IoError::parse(name, line(), msg);
                match clip.as_mut() {
                    None => on_plate(&tag, &parent, &text, &mut plate).map_err(fail)?,
                    Some(_) if tag == "clip" => {
                        let c = clip.take().expect("matched above");
                        if c.is_pressure && pressure.is_none() {
                            let frames = match c.frames {
                                Some(f) => f,
                                None => Frames::new(name, plate)?,
                            };
                            pressure = Some((frames, c.header));
                        }
                    }
                    Some(c) => {
                        on_clip(&tag, &parent, &text, c).map_err(&fail)?;
                        if tag == "quant" && parent.last() == Some(&"data") {
                            let f = frames_of(&mut c.frames, name, plate)?;
                            push_window(f, &c.window).map_err(|e| match e {
                                Ok(msg) => fail(msg),
                                Err(e) => e,
                            })?;
                        }
                    }
                }
                text.clear();
            }
            Event::Eof => break,
            _ => {}
        }
        buf.clear();
    }
    if !path.is_empty() {
        return Err(IoError::parse(
            name,
            line_of(bytes, bytes.len() as u64),
            format!("truncated: the file ends inside <{}>", path.join("><")),
        ));
    }
    match pressure {
        Some((frames, header)) => {
            let mut rec = frames.finish(&header)?;
            rec.format = Some(Format::ZebrisXml);
            Ok(rec)
        }
        None => Err(IoError::format(
            name,
            "no pressure clip (<clip> with <cell_size> or windowed <quant> frames)",
        )),
    }
}

/// The text an entity or character reference stands for.
fn resolve_ref(r: &quick_xml::events::BytesRef) -> String {
    if let Ok(Some(c)) = r.resolve_char_ref() {
        return c.to_string();
    }
    match &**r {
        "amp" => "&",
        "lt" => "<",
        "gt" => ">",
        "quot" => "\"",
        "apos" => "'",
        _ => "",
    }
    .to_string()
}

fn frames_of<'f, 'a>(
    frames: &'f mut Option<Frames<'a>>,
    name: &'a str,
    plate: [Option<usize>; 2],
) -> Result<&'f mut Frames<'a>> {
    if frames.is_none() {
        *frames = Some(Frames::new(name, plate)?);
    }
    Ok(frames.as_mut().expect("set above"))
}

/// Adds the frame of a closed `<quant>`: `Err(Ok(msg))` for a value that is not a number (the
/// caller adds the line), `Err(Err(e))` for a window that does not fit.
fn push_window(
    f: &mut Frames,
    w: &Window,
) -> std::result::Result<(), std::result::Result<String, IoError>> {
    match (&w.cells, w.origin, w.size) {
        (Some(cells), [Some(x), Some(y)], [Some(cw), Some(ch)]) if !cells.trim().is_empty() => {
            let v = values(cells).map_err(|m| Ok(format!("frame {}: {m}", f.n())))?;
            f.push([x, y], [cw, ch], &v).map_err(Err)
        }
        (Some(cells), ..) if !cells.trim().is_empty() => Err(Ok(format!(
            "frame {}: <cells> without its window (<cell_begin> and <cell_count>, x and y)",
            f.n()
        ))),
        _ => {
            f.push_empty();
            Ok(())
        }
    }
}

fn axis(tag: &str) -> Option<usize> {
    match tag {
        "x" => Some(0),
        "y" => Some(1),
        _ => None,
    }
}

/// A closed element outside any clip: the plate's `<measurement><cell_count>`.
fn on_plate(
    tag: &str,
    parent: &[&str],
    text: &str,
    plate: &mut [Option<usize>; 2],
) -> std::result::Result<(), String> {
    if let (Some(a), [.., "measurement", "cell_count"]) = (axis(tag), parent) {
        plate[a] = Some(count(text, "the plate's cell count")?);
    }
    Ok(())
}

/// A closed element inside a clip.
fn on_clip(
    tag: &str,
    parent: &[&str],
    text: &str,
    c: &mut Clip,
) -> std::result::Result<(), String> {
    let h = &mut c.header;
    let w = &mut c.window;
    match (axis(tag), parent) {
        (Some(a), [.., "clip", "cell_size"]) => {
            c.is_pressure = true;
            h.cell_size[a] = Some(
                parse_num(text)
                    .ok_or_else(|| format!("cell size {:?} is not a number", text.trim()))?,
            );
        }
        (Some(a), [.., "quant", "cell_begin"]) => w.origin[a] = Some(count(text, "cell_begin")?),
        (Some(a), [.., "quant", "cell_count"]) => {
            c.is_pressure = true;
            w.size[a] = Some(count(text, "a frame's cell_count")?)
        }
        (None, [.., "clip"]) => match tag {
            "frequency" => {
                h.frequency = Some(parse_num(text).filter(|f| *f > 0.0).ok_or_else(|| {
                    format!("frequency {:?} is not a positive number", text.trim())
                })?)
            }
            "units" => h.units = Some(text.trim().to_string()),
            "count" => h.count = Some(count(text, "the clip's count")?),
            _ => {}
        },
        (None, [.., "quant"]) if tag == "cells" => w.cells = Some(text.to_string()),
        _ => {}
    }
    Ok(())
}

/// Parses TRIPOD's JSON form of the export (already decompressed).
pub fn parse_zebris_json(bytes: &[u8], name: &str) -> Result<Recording> {
    let v: serde_json::Value = serde_json::from_slice(bytes)
        .map_err(|e| IoError::parse(name, e.line(), format!("not valid JSON: {e}")))?;
    let bad = |what: &str| IoError::format(name, format!("{what} is missing or not a number"));
    let int =
        |v: &serde_json::Value, what: &str| v.as_u64().map(|u| u as usize).ok_or_else(|| bad(what));
    let mut h = Header {
        plate: [
            Some(int(&v["cell_count"]["x"], "cell_count.x")?),
            Some(int(&v["cell_count"]["y"], "cell_count.y")?),
        ],
        cell_size: [v["cell_size"]["x"].as_f64(), v["cell_size"]["y"].as_f64()],
        frequency: v["frequency"].as_f64(),
        units: v["pressure_unit"].as_str().map(str::to_string),
        count: None,
    };
    if !v["sample_count"].is_null() {
        h.count = Some(int(&v["sample_count"], "sample_count")?);
    }
    let samples = v["samples"].as_array().ok_or_else(|| bad("samples"))?;
    let mut frames = Frames::new(name, h.plate)?;
    for s in samples {
        let p = s["pressure"].as_array().map(Vec::as_slice).unwrap_or(&[]);
        if p.is_empty() {
            frames.push_empty();
            continue;
        }
        let k = frames.n();
        let field = |v: &serde_json::Value, f: &str| int(v, &format!("frame {k}: {f}"));
        let origin = [
            field(&s["origin"]["x"], "origin.x")?,
            field(&s["origin"]["y"], "origin.y")?,
        ];
        let size = [
            field(&s["size"]["x"], "size.x")?,
            field(&s["size"]["y"], "size.y")?,
        ];
        let values: Vec<f64> = p
            .iter()
            .enumerate()
            .map(|(i, x)| {
                x.as_f64()
                    .ok_or_else(|| bad(&format!("frame {k}: pressure value {i}")))
            })
            .collect::<Result<_>>()?;
        frames.push(origin, size, &values)?;
    }
    let mut rec = frames.finish(&h)?;
    rec.format = Some(Format::ZebrisJson);
    Ok(rec)
}

/// Whether a text head looks like the XML export (`<measurement>` with Zebris clips).
pub(crate) fn sniff_xml(text: &str) -> bool {
    text.trim_start().starts_with('<')
        && text.contains("<measurement")
        && (text.contains("<clip") || text.contains("<cell_count"))
}

/// Whether a text head looks like TRIPOD's JSON form.
pub(crate) fn sniff_json(text: &str) -> bool {
    text.trim_start().starts_with('{')
        && text.contains("\"cell_count\"")
        && text.contains("\"samples\"")
}

/// The format of this module a (decompressed) text head is, if any.
pub(crate) fn sniff(text: &str) -> Option<Format> {
    if sniff_xml(text) {
        Some(Format::ZebrisXml)
    } else if sniff_json(text) {
        Some(Format::ZebrisJson)
    } else {
        None
    }
}
