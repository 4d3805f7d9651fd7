//! TRIPOD's JSON form of the export, read as a stream: one sample is held at a time and placed
//! on the plate as it comes (a JSON tree of the whole file takes tens of times its size). Every
//! field is read as `serde_json::Value` would give it to the readers before (a count is a
//! non-negative integer, a missing field reads as null), without building one.

use super::{Frames, Header, MAX_PLATE_SENSORS};
use crate::error::{IoError, Result};
use crate::formats::stream::read_error;
use crate::recording::{Format, Recording};
use serde::de::{self, DeserializeSeed, Deserializer, IgnoredAny, MapAccess, SeqAccess, Visitor};
use std::fmt;

/// Parses the JSON form from `source` (decompressed already); `name` appears in messages.
pub(super) fn read(source: impl std::io::Read, name: &str) -> Result<Recording> {
    let mut doc = Doc {
        name,
        fields: Fields::default(),
        frames: None,
        failure: None,
    };
    let mut de = serde_json::Deserializer::from_reader(source);
    let parsed = (&mut doc).deserialize(&mut de).and_then(|()| de.end());
    if let Some(e) = doc.failure.take() {
        return Err(e);
    }
    parsed.map_err(|e| match e.is_io() {
        true => read_error(name, std::io::Error::from(e)),
        false => IoError::parse(name, e.line(), format!("not valid JSON: {e}")),
    })?;
    doc.finish()
}

/// A JSON value as far as the reader needs it.
#[derive(Debug, Default, Clone, PartialEq)]
enum Scalar {
    /// Null, or no such field.
    #[default]
    Null,
    /// A non-negative integer.
    Count(u64),
    /// Any other number.
    Number(f64),
    Text(String),
    /// An array, an object or a boolean (skipped as read).
    Other,
}

impl Scalar {
    fn as_u64(&self) -> Option<u64> {
        match *self {
            Scalar::Count(n) => Some(n),
            _ => None,
        }
    }

    fn as_f64(&self) -> Option<f64> {
        match *self {
            Scalar::Count(n) => Some(n as f64),
            Scalar::Number(v) => Some(v),
            _ => None,
        }
    }
}

/// An object's `x` and `y` (null when the value is no object or lacks them).
#[derive(Debug, Default)]
struct Xy {
    x: Scalar,
    y: Scalar,
}

/// The header fields, as read so far.
#[derive(Default)]
struct Fields {
    cell_count: Option<Xy>,
    cell_size: Xy,
    frequency: Scalar,
    pressure_unit: Scalar,
    sample_count: Scalar,
}

/// The document being read.
struct Doc<'a> {
    name: &'a str,
    fields: Fields,
    frames: Option<Frames<'a>>,
    /// The reader's own error that stopped the parse, returned as it is.
    failure: Option<IoError>,
}

impl<'a> Doc<'a> {
    fn bad(&self, what: &str) -> IoError {
        IoError::format(self.name, format!("{what} is missing or not a number"))
    }

    fn count(&self, v: &Scalar, what: &str) -> Result<usize> {
        v.as_u64().map(|u| u as usize).ok_or_else(|| self.bad(what))
    }

    /// The plate as `cell_count` states it.
    fn plate(&self) -> Result<[Option<usize>; 2]> {
        let cc = self.fields.cell_count.as_ref();
        let null = Scalar::Null;
        Ok([
            Some(self.count(cc.map_or(&null, |c| &c.x), "cell_count.x")?),
            Some(self.count(cc.map_or(&null, |c| &c.y), "cell_count.y")?),
        ])
    }

    fn header(&self) -> Result<Header> {
        let f = &self.fields;
        let count = match f.sample_count {
            Scalar::Null => None,
            ref c => Some(self.count(c, "sample_count")?),
        };
        Ok(Header {
            plate: self.plate()?,
            cell_size: [f.cell_size.x.as_f64(), f.cell_size.y.as_f64()],
            frequency: f.frequency.as_f64(),
            units: match &f.pressure_unit {
                Scalar::Text(s) => Some(s.clone()),
                _ => None,
            },
            count,
        })
    }

    /// Stops the parse with `e`, kept to be returned as it is.
    fn fail<E: de::Error>(&mut self, e: IoError) -> E {
        let msg = e.to_string();
        self.failure = Some(e);
        E::custom(msg)
    }

    /// The frames of the `samples` about to be read: placed as they come when the plate is known.
    fn start_frames(&self) -> Result<Frames<'a>> {
        match self.fields.cell_count {
            Some(_) => Frames::new(self.name, self.plate()?),
            None => Ok(Frames::unplaced(self.name)),
        }
    }

    /// Adds one sample as a frame.
    fn sample(&mut self, s: Sample) -> Result<()> {
        let frames = self.frames.as_mut().expect("samples are read into frames");
        let Some(pressure) = s.pressure.filter(|p| !p.is_empty()) else {
            return frames.push_empty();
        };
        let k = frames.n();
        let bad = |what: &str| {
            IoError::format(
                self.name,
                format!("frame {k}: {what} is missing or not a number"),
            )
        };
        let count =
            |v: &Scalar, what: &str| v.as_u64().map(|u| u as usize).ok_or_else(|| bad(what));
        let origin = [
            count(&s.origin.x, "origin.x")?,
            count(&s.origin.y, "origin.y")?,
        ];
        let size = [count(&s.size.x, "size.x")?, count(&s.size.y, "size.y")?];
        let values: Vec<f64> = pressure
            .iter()
            .enumerate()
            .map(|(i, x)| x.ok_or_else(|| bad(&format!("pressure value {i}"))))
            .collect::<Result<_>>()?;
        self.frames
            .as_mut()
            .expect("set")
            .push(origin, size, &values)
    }

    fn finish(self) -> Result<Recording> {
        let h = self.header()?;
        let Some(mut frames) = self.frames else {
            return Err(self.bad("samples"));
        };
        if frames.plate.is_none() {
            frames.set_plate(h.plate)?;
        }
        let mut rec = frames.finish(&h)?;
        rec.format = Some(Format::ZebrisJson);
        Ok(rec)
    }
}

impl<'de> DeserializeSeed<'de> for &mut Doc<'_> {
    type Value = ();
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> std::result::Result<(), D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for &mut Doc<'_> {
    type Value = ();

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a Zebris export object")
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> std::result::Result<(), A::Error> {
        while let Some(key) = map.next_key::<String>()? {
            let f = &mut self.fields;
            match key.as_str() {
                "samples" if self.frames.is_none() => {
                    let frames = self.start_frames().map_err(|e| self.fail(e))?;
                    self.frames = Some(frames);
                    map.next_value_seed(Samples(&mut *self))?;
                }
                "cell_count" => f.cell_count = Some(map.next_value_seed(XySeed)?),
                "cell_size" => f.cell_size = map.next_value_seed(XySeed)?,
                "frequency" => f.frequency = map.next_value_seed(ScalarSeed)?,
                "pressure_unit" => f.pressure_unit = map.next_value_seed(ScalarSeed)?,
                "sample_count" => f.sample_count = map.next_value_seed(ScalarSeed)?,
                _ => drop(map.next_value::<IgnoredAny>()?),
            }
        }
        Ok(())
    }

    // Any other document holds no field: its `cell_count` is missing.
    fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> std::result::Result<(), A::Error> {
        drain(seq)
    }
    fn visit_unit<E: de::Error>(self) -> std::result::Result<(), E> {
        Ok(())
    }
    fn visit_bool<E: de::Error>(self, _: bool) -> std::result::Result<(), E> {
        Ok(())
    }
    fn visit_u64<E: de::Error>(self, _: u64) -> std::result::Result<(), E> {
        Ok(())
    }
    fn visit_i64<E: de::Error>(self, _: i64) -> std::result::Result<(), E> {
        Ok(())
    }
    fn visit_f64<E: de::Error>(self, _: f64) -> std::result::Result<(), E> {
        Ok(())
    }
    fn visit_str<E: de::Error>(self, _: &str) -> std::result::Result<(), E> {
        Ok(())
    }
}

/// Skips the rest of an array.
fn drain<'de, A: SeqAccess<'de>>(mut seq: A) -> std::result::Result<(), A::Error> {
    while seq.next_element::<IgnoredAny>()?.is_some() {}
    Ok(())
}

/// The `samples` array, each sample added to the document's frames as it is read.
struct Samples<'d, 'a>(&'d mut Doc<'a>);

impl<'de> DeserializeSeed<'de> for Samples<'_, '_> {
    type Value = ();
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> std::result::Result<(), D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for Samples<'_, '_> {
    type Value = ();

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("the samples array")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> std::result::Result<(), A::Error> {
        while let Some(s) = seq.next_element_seed(SampleSeed)? {
            self.0.sample(s).map_err(|e| self.0.fail(e))?;
        }
        Ok(())
    }

    // `samples` that is no array: the field is missing.
    fn visit_map<A: MapAccess<'de>>(self, _: A) -> std::result::Result<(), A::Error> {
        Err(self.0.fail(self.0.bad("samples")))
    }
    fn visit_unit<E: de::Error>(self) -> std::result::Result<(), E> {
        Err(self.0.fail(self.0.bad("samples")))
    }
    fn visit_bool<E: de::Error>(self, _: bool) -> std::result::Result<(), E> {
        Err(self.0.fail(self.0.bad("samples")))
    }
    fn visit_u64<E: de::Error>(self, _: u64) -> std::result::Result<(), E> {
        Err(self.0.fail(self.0.bad("samples")))
    }
    fn visit_i64<E: de::Error>(self, _: i64) -> std::result::Result<(), E> {
        Err(self.0.fail(self.0.bad("samples")))
    }
    fn visit_f64<E: de::Error>(self, _: f64) -> std::result::Result<(), E> {
        Err(self.0.fail(self.0.bad("samples")))
    }
    fn visit_str<E: de::Error>(self, _: &str) -> std::result::Result<(), E> {
        Err(self.0.fail(self.0.bad("samples")))
    }
}

/// One sample: its window and pressures (`None`: no array, an unloaded frame).
#[derive(Default)]
struct Sample {
    origin: Xy,
    size: Xy,
    /// Each value, `None` where it is no number.
    pressure: Option<Vec<Option<f64>>>,
}

struct SampleSeed;

impl<'de> DeserializeSeed<'de> for SampleSeed {
    type Value = Sample;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> std::result::Result<Sample, D::Error> {
        d.deserialize_any(SampleVisitor)
    }
}

struct SampleVisitor;

impl<'de> Visitor<'de> for SampleVisitor {
    type Value = Sample;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a sample")
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> std::result::Result<Sample, A::Error> {
        let mut s = Sample::default();
        while let Some(key) = map.next_key::<String>()? {
            match key.as_str() {
                "origin" => s.origin = map.next_value_seed(XySeed)?,
                "size" => s.size = map.next_value_seed(XySeed)?,
                "pressure" => s.pressure = map.next_value_seed(PressureSeed)?,
                _ => drop(map.next_value::<IgnoredAny>()?),
            }
        }
        Ok(s)
    }

    // A sample that is no object has no pressures: an unloaded frame.
    fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> std::result::Result<Sample, A::Error> {
        drain(seq).map(|()| Sample::default())
    }
    fn visit_unit<E: de::Error>(self) -> std::result::Result<Sample, E> {
        Ok(Sample::default())
    }
    fn visit_bool<E: de::Error>(self, _: bool) -> std::result::Result<Sample, E> {
        Ok(Sample::default())
    }
    fn visit_u64<E: de::Error>(self, _: u64) -> std::result::Result<Sample, E> {
        Ok(Sample::default())
    }
    fn visit_i64<E: de::Error>(self, _: i64) -> std::result::Result<Sample, E> {
        Ok(Sample::default())
    }
    fn visit_f64<E: de::Error>(self, _: f64) -> std::result::Result<Sample, E> {
        Ok(Sample::default())
    }
    fn visit_str<E: de::Error>(self, _: &str) -> std::result::Result<Sample, E> {
        Ok(Sample::default())
    }
}

/// A sample's `pressure`: an array of at most one plate's values (`None` for anything else).
struct PressureSeed;

impl<'de> DeserializeSeed<'de> for PressureSeed {
    type Value = Option<Vec<Option<f64>>>;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> std::result::Result<Self::Value, D::Error> {
        match d.deserialize_any(ScalarVisitor { values: true })? {
            Parsed::Values(v) => Ok(Some(v)),
            Parsed::Scalar(_) => Ok(None),
        }
    }
}

/// An object's `x` and `y`.
struct XySeed;

impl<'de> DeserializeSeed<'de> for XySeed {
    type Value = Xy;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> std::result::Result<Xy, D::Error> {
        d.deserialize_any(XyVisitor)
    }
}

struct XyVisitor;

impl<'de> Visitor<'de> for XyVisitor {
    type Value = Xy;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("an object with x and y")
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> std::result::Result<Xy, A::Error> {
        let mut xy = Xy::default();
        while let Some(key) = map.next_key::<String>()? {
            match key.as_str() {
                "x" => xy.x = map.next_value_seed(ScalarSeed)?,
                "y" => xy.y = map.next_value_seed(ScalarSeed)?,
                _ => drop(map.next_value::<IgnoredAny>()?),
            }
        }
        Ok(xy)
    }

    // Anything else has no x nor y.
    fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> std::result::Result<Xy, A::Error> {
        drain(seq).map(|()| Xy::default())
    }
    fn visit_unit<E: de::Error>(self) -> std::result::Result<Xy, E> {
        Ok(Xy::default())
    }
    fn visit_bool<E: de::Error>(self, _: bool) -> std::result::Result<Xy, E> {
        Ok(Xy::default())
    }
    fn visit_u64<E: de::Error>(self, _: u64) -> std::result::Result<Xy, E> {
        Ok(Xy::default())
    }
    fn visit_i64<E: de::Error>(self, _: i64) -> std::result::Result<Xy, E> {
        Ok(Xy::default())
    }
    fn visit_f64<E: de::Error>(self, _: f64) -> std::result::Result<Xy, E> {
        Ok(Xy::default())
    }
    fn visit_str<E: de::Error>(self, _: &str) -> std::result::Result<Xy, E> {
        Ok(Xy::default())
    }
}

/// One value, read as a [`Scalar`].
struct ScalarSeed;

impl<'de> DeserializeSeed<'de> for ScalarSeed {
    type Value = Scalar;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> std::result::Result<Scalar, D::Error> {
        match d.deserialize_any(ScalarVisitor { values: false })? {
            Parsed::Scalar(s) => Ok(s),
            Parsed::Values(_) => Ok(Scalar::Other),
        }
    }
}

/// What [`ScalarVisitor`] read.
enum Parsed {
    Scalar(Scalar),
    /// An array's values as numbers (when asked for).
    Values(Vec<Option<f64>>),
}

/// Reads one value; an array's values as numbers when `values` (a sample's pressures, at most
/// one plate's: a longer array is refused while it is read), else skipped.
struct ScalarVisitor {
    values: bool,
}

impl<'de> Visitor<'de> for ScalarVisitor {
    type Value = Parsed;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a JSON value")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> std::result::Result<Parsed, A::Error> {
        if !self.values {
            return drain(seq).map(|()| Parsed::Scalar(Scalar::Other));
        }
        let mut v = Vec::new();
        while let Some(x) = seq.next_element_seed(ScalarSeed)? {
            if v.len() == MAX_PLATE_SENSORS {
                return Err(de::Error::custom(format!(
                    "more than the {MAX_PLATE_SENSORS} pressure values of a plate in one sample"
                )));
            }
            v.push(x.as_f64());
        }
        Ok(Parsed::Values(v))
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> std::result::Result<Parsed, A::Error> {
        while map.next_entry::<IgnoredAny, IgnoredAny>()?.is_some() {}
        Ok(Parsed::Scalar(Scalar::Other))
    }
    fn visit_unit<E: de::Error>(self) -> std::result::Result<Parsed, E> {
        Ok(Parsed::Scalar(Scalar::Null))
    }
    fn visit_bool<E: de::Error>(self, _: bool) -> std::result::Result<Parsed, E> {
        Ok(Parsed::Scalar(Scalar::Other))
    }
    fn visit_u64<E: de::Error>(self, v: u64) -> std::result::Result<Parsed, E> {
        Ok(Parsed::Scalar(Scalar::Count(v)))
    }
    fn visit_i64<E: de::Error>(self, v: i64) -> std::result::Result<Parsed, E> {
        // Non-negative integers arrive as `u64`: a negative one is a number, no count.
        Ok(Parsed::Scalar(Scalar::Number(v as f64)))
    }
    fn visit_f64<E: de::Error>(self, v: f64) -> std::result::Result<Parsed, E> {
        Ok(Parsed::Scalar(Scalar::Number(v)))
    }
    fn visit_str<E: de::Error>(self, v: &str) -> std::result::Result<Parsed, E> {
        Ok(Parsed::Scalar(Scalar::Text(v.to_string())))
    }
}
