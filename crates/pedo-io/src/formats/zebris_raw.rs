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
use super::stream::{bounded, read_error, Stretch};
use crate::error::{IoError, Result};
use crate::limits::{current, raise};
use crate::recording::stated_units;
use crate::recording::{Format, Recording, SparseFrames};
use quick_xml::events::Event;
use quick_xml::Reader;

mod json;

/// Plates larger than this many sensors are refused before anything is allocated: the largest
/// Zebris platforms and treadmills hold about 12,000, and every frame costs the whole plate.
const MAX_PLATE_SENSORS: usize = 1 << 16;

/// Elements nested deeper than this are refused: the export nests about eight deep, and each
/// open element's name is held.
const MAX_DEPTH: usize = 256;

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

/// The frames of one clip as they are read, placed on the plate (held sparsely) as soon as its
/// size is known: so that a frame costs the values its window holds, not the whole plate.
struct Frames<'a> {
    name: &'a str,
    /// `(cols, rows)` once known.
    plate: Option<(usize, usize)>,
    placed: SparseFrames,
    /// The loaded frames read before the plate's size (a JSON export whose `samples` come
    /// before its `cell_count`): each frame's number and window `[x, y, w, h]`, its values in
    /// `waiting_values`; the frames between are unloaded.
    waiting: Vec<(u32, [u32; 4])>,
    waiting_values: Vec<f32>,
    n: usize,
}

impl<'a> Frames<'a> {
    /// Frames on a plate whose size is not known yet.
    fn unplaced(name: &'a str) -> Self {
        Frames {
            name,
            plate: None,
            placed: SparseFrames::new(0),
            waiting: Vec::new(),
            waiting_values: Vec::new(),
            n: 0,
        }
    }

    /// Frames on the plate of `plate` (`[x, y]` sensors, as read).
    fn new(name: &'a str, plate: [Option<usize>; 2]) -> Result<Self> {
        let mut f = Frames::unplaced(name);
        f.set_plate(plate)?;
        Ok(f)
    }

    /// The plate's size, `[x, y]` as read: the frames read so far are placed on it.
    fn set_plate(&mut self, plate: [Option<usize>; 2]) -> Result<()> {
        let [Some(cols), Some(rows)] = plate else {
            return Err(IoError::format(
                self.name,
                "a frame before the plate's <cell_count> (x and y)",
            ));
        };
        if cols == 0 || rows == 0 || cols.saturating_mul(rows) > MAX_PLATE_SENSORS {
            return Err(IoError::format(
                self.name,
                format!("a plate of {cols} x {rows} sensors is not a pressure plate"),
            ));
        }
        crate::limits::check_frames(self.name, self.n, cols * rows)?;
        self.plate = Some((cols, rows));
        self.placed = SparseFrames::new(cols * rows);
        let waiting = std::mem::take(&mut self.waiting);
        let values = std::mem::take(&mut self.waiting_values);
        let mut at = 0;
        for &(k, [x, y, w, h]) in &waiting {
            let [k, x, y, w, h] = [k, x, y, w, h].map(|v| v as usize);
            while self.placed.n_frames() < k {
                self.placed.push_empty();
            }
            self.place(k, [x, y], [w, h], &values[at..at + w * h])?;
            at += w * h;
        }
        while self.placed.n_frames() < self.n {
            self.placed.push_empty();
        }
        Ok(())
    }

    /// Adds one frame (`values` x fastest in the window of `size` at `origin`).
    fn push(&mut self, origin: [usize; 2], size: [usize; 2], values: &[f64]) -> Result<()> {
        let k = self.n;
        let err = |msg: String| IoError::format(self.name, format!("frame {k}: {msg}"));
        let [w, h] = size;
        if let Some((cols, rows)) = self.plate
            && (origin[0].saturating_add(w) > cols || origin[1].saturating_add(h) > rows)
        {
            return Err(err(format!(
                "the window at ({}, {}) of {w} x {h} sensors leaves the {cols} x {rows} plate",
                origin[0], origin[1]
            )));
        }
        if values.len() != w.saturating_mul(h) {
            return Err(err(format!(
                "{} values for a window of {w} x {h} = {} sensors",
                values.len(),
                w.saturating_mul(h)
            )));
        }
        if let Some(i) = values.iter().position(|v| *v < 0.0) {
            return Err(err(format!("value {i} is negative ({})", values[i])));
        }
        if w == 0 || h == 0 {
            return self.push_empty();
        }
        self.count_frame()?;
        let v: Vec<f32> = values.iter().map(|&x| x as f32).collect();
        if self.plate.is_some() {
            return self.place(k, origin, size, &v);
        }
        // No window of a plate's sensors is larger than the largest plate.
        let window = [origin[0], origin[1], w, h].map(|v| u32::try_from(v).ok());
        let [Some(x), Some(y), Some(w), Some(h)] = window else {
            return Err(err(format!(
                "the window at ({}, {}) of {w} x {h} sensors leaves any plate",
                origin[0], origin[1]
            )));
        };
        // Frames are numbered within `limits::MAX_FRAMES`, far below `u32::MAX`.
        self.waiting.push((k as u32, [x, y, w, h]));
        self.waiting_values.extend_from_slice(&v);
        Ok(())
    }

    fn push_empty(&mut self) -> Result<()> {
        self.count_frame()?;
        if self.plate.is_some() {
            self.placed.push_empty();
        }
        Ok(())
    }

    /// Counts a frame more, within the limits of a recording.
    fn count_frame(&mut self) -> Result<()> {
        let per = self.plate.map_or(1, |(c, r)| c * r);
        crate::limits::check_frames(self.name, self.n + 1, per)?;
        self.n += 1;
        Ok(())
    }

    /// Places frame `k` on the plate: its window's values, row 0 at the plate's far end.
    fn place(&mut self, k: usize, origin: [usize; 2], size: [usize; 2], v: &[f32]) -> Result<()> {
        let (cols, rows) = self.plate.expect("placed on a known plate");
        let [w, h] = size;
        if origin[0].saturating_add(w) > cols || origin[1].saturating_add(h) > rows {
            return Err(IoError::format(
                self.name,
                format!(
                    "frame {k}: the window at ({}, {}) of {w} x {h} sensors leaves the {cols} x \
                     {rows} plate",
                    origin[0], origin[1]
                ),
            ));
        }
        if w == 0 || h == 0 {
            self.placed.push_empty();
            return Ok(());
        }
        // The window's rows, from the plate's far end (row 0).
        let row_start = |j: usize| (rows - 1 - (origin[1] + j)) * cols + origin[0];
        let mut entries: Vec<(usize, f32)> = v
            .chunks(w)
            .enumerate()
            .flat_map(|(j, line)| {
                line.iter()
                    .enumerate()
                    .map(move |(i, &x)| (row_start(j) + i, x))
            })
            .collect();
        self.placed.push_entries(&mut entries);
        Ok(())
    }

    fn n(&self) -> usize {
        self.n
    }

    /// The recording: every frame the whole plate, row 0 at the plate's far end.
    fn finish(self, h: &Header) -> Result<Recording> {
        let n = self.n;
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
        let Some((cols, rows)) = self.plate else {
            return Err(IoError::format(self.name, "no plate size (cell_count)"));
        };
        let mut rec = Recording::from_sparse(rows, cols, self.placed, vec![true; rows * cols])?;
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

/// The line breaks in what an XML event was read from (its markup or text).
fn newlines(event: &Event) -> usize {
    event.bytes().filter(|&b| b == b'\n').count()
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
    read_zebris_xml(bounded(bytes, false, Stretch::Xml), name)
}

/// The bytes of one XML event (a tag, a comment, a CDATA section, a processing instruction)
/// bounded by the text limit: the parser holds an event whole before it hands it over, and a
/// comment or CDATA section may hold any byte but its end (`<` and `>` included), so no byte
/// of the stream bounds it. The reader resets `spent` after every event.
struct EventBudget<R> {
    inner: R,
    spent: usize,
    most: usize,
}

impl<R> EventBudget<R> {
    fn new(inner: R, most: usize) -> Self {
        Self {
            inner,
            spent: 0,
            most,
        }
    }
}

impl<R> EventBudget<R> {
    fn over(&self) -> std::io::Result<()> {
        if self.spent > self.most {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                format!(
                    "an XML element, comment or CDATA section longer than {} bytes: no export \
                     of this format; {}",
                    self.most,
                    raise("max_text_mb")
                ),
            ));
        }
        Ok(())
    }
}

impl<R: std::io::Read> std::io::Read for EventBudget<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        self.over()?;
        let n = self.inner.read(buf)?;
        self.spent = self.spent.saturating_add(n);
        Ok(n)
    }
}

impl<R: std::io::BufRead> std::io::BufRead for EventBudget<R> {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        self.over()?;
        self.inner.fill_buf()
    }
    fn consume(&mut self, n: usize) {
        // Counted here, refused at the next fill: `consume` cannot fail.
        self.spent = self.spent.saturating_add(n);
        self.inner.consume(n);
    }
}

/// Parses the XML raw-data export as it is read from `source`: only the open elements' names,
/// the element being read and the frames (sparse) are held; the work per element does not grow
/// with the depth of nesting.
pub(crate) fn read_zebris_xml(source: impl std::io::BufRead, name: &str) -> Result<Recording> {
    let most_text = current().text;
    let mut reader = Reader::from_reader(EventBudget::new(source, most_text));
    let mut path: Vec<String> = Vec::new();
    let mut text = String::new();
    let mut plate: [Option<usize>; 2] = [None, None];
    let mut clip: Option<Clip> = None;
    let mut pressure: Option<(Frames, Header)> = None;
    let mut buf = Vec::new();
    // The line the next event starts on: 1 and the line breaks of the events before it.
    let mut line = 1;
    loop {
        let event = match reader.read_event_into(&mut buf) {
            Ok(event) => event,
            Err(quick_xml::Error::Io(e)) => {
                return Err(read_error(
                    name,
                    std::io::Error::new(e.kind(), e.to_string()),
                ));
            }
            Err(e) => {
                let msg = format!("malformed or truncated XML: {e}");
                return Err(IoError::parse(name, line, msg));
            }
        };
        let at = line;
        line += newlines(&event);
        let fail = |msg: String| IoError::parse(name, at, msg);
        match event {
            Event::Start(e) => {
                if path.len() == MAX_DEPTH {
                    return Err(fail(format!(
                        "more than {MAX_DEPTH} nested elements: not a Zebris export"
                    )));
                }
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
                    frames_of(&mut c.frames, name, plate)?.push_empty()?;
                }
            }
            Event::Text(t) => text.push_str(&t),
            Event::CData(t) => text.push_str(&t),
            Event::GeneralRef(r) => text.push_str(&resolve_ref(&r)),
            Event::End(_) => {
                let Some(tag) = path.pop() else {
                    return Err(fail("a closing tag without an opening one".into()));
                };
                // The two enclosing elements are all a closed element's meaning depends on.
                let parent: Vec<&str> = path[path.len().saturating_sub(2)..]
                    .iter()
                    .map(String::as_str)
                    .collect();
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
                        on_clip(&tag, &parent, &text, c).map_err(fail)?;
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
        if text.len() > most_text {
            return Err(fail(format!(
                "an element holds more than {most_text} bytes of text; {}",
                raise("max_text_mb")
            )));
        }
        buf.clear();
        reader.get_mut().spent = 0;
    }
    if !path.is_empty() {
        return Err(IoError::parse(
            name,
            line,
            format!("truncated: the file ends inside {}", open_elements(&path)),
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

/// The elements open at the end of a cut file, outermost first (`<measurement><movements>`);
/// of a deep nesting the outermost and innermost few, and how many.
fn open_elements(path: &[String]) -> String {
    let tags = |p: &[String]| p.iter().map(|t| format!("<{t}>")).collect::<String>();
    if path.len() <= 8 {
        return tags(path);
    }
    let n = path.len();
    format!(
        "{}…{} ({n} elements)",
        tags(&path[..4]),
        tags(&path[n - 2..])
    )
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
        _ => f.push_empty().map_err(Err),
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
    read_zebris_json(bounded(bytes, false, Stretch::Json), name)
}

/// Parses TRIPOD's JSON form as it is read from `source` (decompressed already).
pub(crate) fn read_zebris_json(source: impl std::io::Read, name: &str) -> Result<Recording> {
    json::read(source, name)
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
