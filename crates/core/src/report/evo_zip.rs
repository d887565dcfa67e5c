//! evo's result files: the zip archives `evo_ape`/`evo_rpe --save_results` write and `evo_res` reads,
//! written by `trajdrift ape|rpe --save_results` and read by `trajdrift res`.
//!
//! What evo 1.38.1 writes (`evo.tools.file_interface.save_res_file`, seen by running it): a zip of
//! stored (uncompressed) members `info.json` (`title`, `ref_name`, `est_name`, `label`), `stats.json`
//! (`rmse`, `mean`, `median`, `std`, `min`, `max`, `sse`, in that order) and one `NAME.npy` per array:
//! `error_array`, then for stamped trajectories `seconds_from_start`, `timestamps`,
//! `distances_from_start` (the reference's path length), `distances` (the estimate's), and with an
//! alignment `alignment_transformation_sim3` (4×4). JSON is written as Python's `json.dumps` writes it
//! (`", "`/`": "` separators, ASCII with `\uXXXX` escapes, floats in Python's `repr`), so the members
//! are byte for byte what evo writes for the same numbers. Reading keeps the members' key order (the
//! order of evo_res's table); members must be stored, as evo (Python's `zipfile` default) writes them
//! (a compressed member is a one-line error naming it); every member's size is checked against the
//! archive before it is read.

use std::io::{Read, Write};
use std::path::Path;

use serde_json::Value;

use super::npy::{read_npy, write_npy, NpyArray};
use crate::error::{Error, Result};

/// One result: evo's `Result` object (info, stats, arrays; backup trajectories are not kept).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct EvoResult {
    /// `info.json`, in its order.
    pub info: Vec<(String, Value)>,
    /// `stats.json`, in its order.
    pub stats: Vec<(String, f64)>,
    /// The `.npy` members, by name without the extension, in archive order.
    pub arrays: Vec<(String, NpyArray)>,
}

impl EvoResult {
    /// An info field as text (`title`, `est_name`, `ref_name`, `label`).
    pub fn info_str(&self, key: &str) -> Option<&str> {
        self.info
            .iter()
            .find(|(k, _)| k == key)
            .and_then(|(_, v)| v.as_str())
    }

    /// A statistic.
    pub fn stat(&self, key: &str) -> Option<f64> {
        self.stats.iter().find(|(k, _)| k == key).map(|(_, v)| *v)
    }

    /// An array by name.
    pub fn array(&self, key: &str) -> Option<&NpyArray> {
        self.arrays.iter().find(|(k, _)| k == key).map(|(_, a)| a)
    }

    /// Adds a one-dimensional array.
    pub fn push_array(&mut self, name: &str, values: Vec<f64>) {
        self.arrays.push((
            name.to_string(),
            NpyArray {
                shape: vec![values.len()],
                data: values,
            },
        ));
    }

    /// The archive's bytes, as evo writes them (stored members, evo's member order).
    pub fn to_zip(&self) -> Result<Vec<u8>> {
        let mut cursor = std::io::Cursor::new(Vec::new());
        {
            let mut zip = zip::ZipWriter::new(&mut cursor);
            let options = zip::write::SimpleFileOptions::default()
                .compression_method(zip::CompressionMethod::Stored);
            let mut member = |name: &str, bytes: &[u8]| -> Result<()> {
                zip.start_file(name, options)
                    .map_err(|e| Error::Metric(format!("writing {name}: {e}")))?;
                zip.write_all(bytes)
                    .map_err(|e| Error::Metric(format!("writing {name}: {e}")))
            };
            member("info.json", py_json_object(&self.info).as_bytes())?;
            let stats: Vec<(String, Value)> = self
                .stats
                .iter()
                .map(|(k, v)| (k.clone(), float_value(*v)))
                .collect();
            member("stats.json", py_json_object(&stats).as_bytes())?;
            for (name, a) in &self.arrays {
                member(&format!("{name}.npy"), &write_npy(&a.shape, &a.data))?;
            }
            zip.finish()
                .map_err(|e| Error::Metric(format!("finishing the zip: {e}")))?;
        }
        Ok(cursor.into_inner())
    }

    /// Reads a result file written by evo or trajdrift.
    pub fn read(path: &Path) -> Result<EvoResult> {
        let bytes = std::fs::read(path).map_err(|cause| Error::Io {
            path: path.to_path_buf(),
            cause,
        })?;
        Self::from_zip(&bytes).map_err(|detail| {
            Error::Metric(format!(
                "{}: {detail}; expected a result file of `--save_results` (evo_ape/evo_rpe or trajdrift ape/rpe)",
                path.display()
            ))
        })
    }

    /// Parses an archive's bytes.
    pub fn from_zip(bytes: &[u8]) -> std::result::Result<EvoResult, String> {
        let mut zip = zip::ZipArchive::new(std::io::Cursor::new(bytes))
            .map_err(|e| format!("not a zip archive ({e})"))?;
        let names: Vec<String> = zip.file_names().map(str::to_string).collect();
        if !names.iter().any(|n| n == "info.json") || !names.iter().any(|n| n == "stats.json") {
            return Err("not a valid result file (no info.json and stats.json)".into());
        }
        let mut member = |name: &str| -> std::result::Result<Vec<u8>, String> {
            let f = zip.by_name(name).map_err(|e| format!("{name}: {e}"))?;
            // Deflate expands at most 1032:1; a declared size beyond that, or a member larger than
            // the archive, is damage: refused before anything is allocated.
            let limit = f.compressed_size().saturating_mul(1032).saturating_add(64);
            if f.compressed_size() > bytes.len() as u64 || f.size() > limit {
                return Err(format!(
                    "{name}: declared size {} does not fit the archive",
                    f.size()
                ));
            }
            let mut out = Vec::with_capacity(f.size() as usize);
            f.take(limit)
                .read_to_end(&mut out)
                .map_err(|e| format!("{name}: {e}"))?;
            Ok(out)
        };
        let info = ordered_object(&member("info.json")?).map_err(|e| format!("info.json: {e}"))?;
        let stats = ordered_object(&member("stats.json")?)
            .map_err(|e| format!("stats.json: {e}"))?
            .into_iter()
            .filter_map(|(k, v)| v.as_f64().map(|f| (k, f)))
            .collect();
        let mut arrays = Vec::new();
        for name in &names {
            let Some(stem) = name
                .strip_suffix(".npy")
                .or_else(|| name.strip_suffix(".npz"))
            else {
                continue;
            };
            let a = read_npy(&member(name)?).map_err(|e| format!("{name}: {e}"))?;
            arrays.push((stem.to_string(), a));
        }
        Ok(EvoResult {
            info,
            stats,
            arrays,
        })
    }
}

/// A JSON object's members in file order (serde_json's map is sorted without its
/// `preserve_order` feature, and the order is evo_res's column order).
fn ordered_object(bytes: &[u8]) -> std::result::Result<Vec<(String, Value)>, String> {
    struct Ordered(Vec<(String, Value)>);
    impl<'de> serde::Deserialize<'de> for Ordered {
        fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
            struct V;
            impl<'de> serde::de::Visitor<'de> for V {
                type Value = Ordered;
                fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                    f.write_str("a JSON object")
                }
                fn visit_map<A: serde::de::MapAccess<'de>>(
                    self,
                    mut m: A,
                ) -> std::result::Result<Ordered, A::Error> {
                    let mut v = Vec::new();
                    while let Some((k, x)) = m.next_entry::<String, Value>()? {
                        v.push((k, x));
                    }
                    Ok(Ordered(v))
                }
            }
            d.deserialize_map(V)
        }
    }
    // Python's json writes NaN and Infinity bare; serde_json does not read them.
    let text = String::from_utf8_lossy(bytes)
        .replace("-Infinity", "-1e999")
        .replace("Infinity", "1e999")
        .replace("NaN", "null");
    serde_json::from_str::<Ordered>(&text)
        .map(|o| o.0)
        .map_err(|e| e.to_string())
}

fn float_value(v: f64) -> Value {
    serde_json::Number::from_f64(v).map_or(Value::Null, Value::Number)
}

/// An object as Python's `json.dumps` writes it.
fn py_json_object(members: &[(String, Value)]) -> String {
    let body: Vec<String> = members
        .iter()
        .map(|(k, v)| format!("{}: {}", py_json_string(k), py_json_value(v)))
        .collect();
    format!("{{{}}}", body.join(", "))
}

fn py_json_value(v: &Value) -> String {
    match v {
        Value::String(s) => py_json_string(s),
        Value::Number(n) => match n.as_f64() {
            Some(f) if !n.is_i64() && !n.is_u64() => py_float(f),
            _ => n.to_string(),
        },
        Value::Bool(b) => if *b { "true" } else { "false" }.into(),
        Value::Null => "NaN".into(),
        Value::Array(a) => format!(
            "[{}]",
            a.iter().map(py_json_value).collect::<Vec<_>>().join(", ")
        ),
        Value::Object(o) => py_json_object(
            &o.iter()
                .map(|(k, v)| (k.clone(), v.clone()))
                .collect::<Vec<_>>(),
        ),
    }
}

/// A string as `json.dumps` (ensure_ascii) writes it.
fn py_json_string(s: &str) -> String {
    let mut out = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            '\u{8}' => out.push_str("\\b"),
            '\u{c}' => out.push_str("\\f"),
            c if (c as u32) < 0x20 || (c as u32) > 0x7e => {
                let mut buf = [0u16; 2];
                for u in c.encode_utf16(&mut buf) {
                    out.push_str(&format!("\\u{u:04x}"));
                }
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// A float as Python's `repr` writes it: the shortest digits that read back to it, positional for
/// decimal exponents from -4 to 15 (`0.0001`, `1e-05`, `1000000000000000.0`, `1e+16`).
///
/// ```
/// use trajdrift_core::report::evo_zip::py_float;
/// assert_eq!(py_float(1.0), "1.0");
/// assert_eq!(py_float(0.00001), "1e-05");
/// assert_eq!(py_float(0.0001), "0.0001");
/// assert_eq!(py_float(7715.07344), "7715.07344");
/// assert_eq!(py_float(1e16), "1e+16");
/// assert_eq!(py_float(-2.5e-7), "-2.5e-07");
/// assert_eq!(py_float(f64::NAN), "nan");
/// ```
pub fn py_float(v: f64) -> String {
    if v.is_nan() {
        return "nan".into();
    }
    if v.is_infinite() {
        return if v > 0.0 { "inf" } else { "-inf" }.into();
    }
    if v == 0.0 {
        return if v.is_sign_negative() { "-0.0" } else { "0.0" }.into();
    }
    let sci = format!("{:e}", v.abs());
    let (mantissa, exp) = sci.split_once('e').unwrap_or((&sci, "0"));
    let exp: i32 = exp.parse().unwrap_or(0);
    let digits: String = mantissa.chars().filter(|c| c.is_ascii_digit()).collect();
    let sign = if v < 0.0 { "-" } else { "" };
    if !(-4..16).contains(&exp) {
        let m = if digits.len() > 1 {
            format!("{}.{}", &digits[..1], &digits[1..])
        } else {
            digits
        };
        let es = if exp < 0 { '-' } else { '+' };
        return format!("{sign}{m}e{es}{:02}", exp.abs());
    }
    let point = exp + 1; // digits before the decimal point
    let body = if point <= 0 {
        format!("0.{}{digits}", "0".repeat((-point) as usize))
    } else if point as usize >= digits.len() {
        format!("{digits}{}.0", "0".repeat(point as usize - digits.len()))
    } else {
        format!(
            "{}.{}",
            &digits[..point as usize],
            &digits[point as usize..]
        )
    };
    format!("{sign}{body}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_members_are_pythons() {
        let info = vec![
            (
                "title".to_string(),
                Value::from("APE w.r.t. translation part (m)\n(not aligned)"),
            ),
            ("est_name".to_string(), Value::from("caf\u{e9}.txt")),
        ];
        assert_eq!(
            py_json_object(&info),
            r#"{"title": "APE w.r.t. translation part (m)\n(not aligned)", "est_name": "caf\u00e9.txt"}"#
        );
        assert_eq!(py_float(0.008118977562045396), "0.008118977562045396");
        assert_eq!(py_float(0.14330528992361463), "0.14330528992361463");
        assert_eq!(py_float(123456789012345680.0), "1.2345678901234568e+17");
        assert_eq!(py_float(100.0), "100.0");
    }

    #[test]
    fn round_trip_keeps_order_and_arrays() {
        let mut r = EvoResult {
            info: vec![
                ("title".into(), Value::from("t")),
                ("label".into(), Value::from("APE (m)")),
            ],
            stats: vec![
                ("rmse".into(), 2.0),
                ("mean".into(), 1.5),
                ("max".into(), 3.0),
            ],
            arrays: Vec::new(),
        };
        r.push_array("error_array", vec![1.0, 2.0, 3.0]);
        let back = EvoResult::from_zip(&r.to_zip().unwrap()).unwrap();
        assert_eq!(back, r);
        assert!(EvoResult::from_zip(b"not a zip").is_err());
    }
}
