//! NumPy's `.npy` format for the float arrays of evo's result files (`error_array.npy`,
//! `timestamps.npy`, the 4×4 `alignment_transformation_sim3.npy`, ...).
//!
//! Hand-written on purpose: the format is a 10-byte preamble and a Python dict literal
//! (<https://numpy.org/doc/stable/reference/generated/numpy.lib.format.html>), and the crates that
//! implement it (npyz) parse that literal with a general Python-literal parser (pest and a bignum
//! crate) for the one header shape evo writes. We write exactly what `np.save` writes for a
//! little-endian float64 C-order array (version 1.0, header padded to 64 bytes), and read float64
//! (either byte order), float32 and integer arrays of any shape, every length checked against the
//! bytes present before anything is allocated.
//!
//! ```
//! use trajdrift_core::report::npy::{read_npy, write_npy};
//! let bytes = write_npy(&[2, 2], &[1.0, 2.0, 3.0, 4.0]);
//! assert_eq!(&bytes[..6], b"\x93NUMPY");
//! assert_eq!(bytes.len() % 64, 32); // a 64-byte header, then 32 bytes of data
//! let a = read_npy(&bytes).unwrap();
//! assert_eq!((a.shape, a.data), (vec![2, 2], vec![1.0, 2.0, 3.0, 4.0]));
//! ```

/// An array read from a `.npy` file, as float64 in C order.
#[derive(Debug, Clone, PartialEq)]
pub struct NpyArray {
    pub shape: Vec<usize>,
    pub data: Vec<f64>,
}

/// The bytes `np.save` writes for a float64 array of `shape` (C order; `data.len()` must be the
/// product of `shape`).
pub fn write_npy(shape: &[usize], data: &[f64]) -> Vec<u8> {
    let dims = match shape {
        [n] => format!("({n},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(|d| d.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    let mut header = format!("{{'descr': '<f8', 'fortran_order': False, 'shape': {dims}, }}");
    // Preamble (10 bytes) + header + '\n' is a multiple of 64, as numpy pads it.
    let unpadded = 10 + header.len() + 1;
    header.push_str(&" ".repeat((64 - unpadded % 64) % 64));
    header.push('\n');
    let mut out = Vec::with_capacity(10 + header.len() + 8 * data.len());
    out.extend_from_slice(b"\x93NUMPY\x01\x00");
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    for v in data {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out
}

/// Reads a `.npy` file's bytes (versions 1–3; float64, float32 or integer elements, C order).
pub fn read_npy(bytes: &[u8]) -> Result<NpyArray, String> {
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        return Err("not a .npy array (no \\x93NUMPY magic)".into());
    }
    let (header_len, start): (usize, usize) = match bytes[6] {
        1 => (u16::from_le_bytes([bytes[8], bytes[9]]) as usize, 10),
        2 | 3 if bytes.len() >= 12 => (
            u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
            12,
        ),
        v => return Err(format!(".npy version {v} is not supported")),
    };
    let header = bytes
        .get(start..start.saturating_add(header_len))
        .ok_or("the .npy header is longer than the file")?;
    let header = std::str::from_utf8(header).map_err(|_| "the .npy header is not text")?;
    let descr = dict_value(header, "descr").ok_or("the .npy header has no 'descr'")?;
    let descr = descr.trim_matches(|c| c == '\'' || c == '"');
    if dict_value(header, "fortran_order").is_some_and(|v| v.starts_with("True")) {
        return Err("Fortran-ordered .npy arrays are not supported".into());
    }
    let shape_text = dict_value(header, "shape").ok_or("the .npy header has no 'shape'")?;
    let inner = shape_text
        .strip_prefix('(')
        .and_then(|s| s.split(')').next())
        .ok_or("the .npy 'shape' is not a tuple")?;
    let shape = inner
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| {
            s.parse::<usize>()
                .map_err(|_| format!("bad .npy dimension {s:?}"))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let count = shape
        .iter()
        .try_fold(1usize, |a, &d| a.checked_mul(d))
        .ok_or("the .npy shape overflows")?;
    let (little, kind, size) = parse_descr(descr)?;
    let body = &bytes[start + header_len..];
    let need = count.checked_mul(size).ok_or("the .npy shape overflows")?;
    if body.len() < need {
        return Err(format!(
            "the .npy array holds {} bytes, its shape {:?} needs {need}",
            body.len(),
            shape
        ));
    }
    let data = body[..need]
        .chunks_exact(size)
        .map(|c| element(c, little, kind))
        .collect();
    Ok(NpyArray { shape, data })
}

/// The text after `'key':` in the header dict, up to the next top-level comma.
fn dict_value<'a>(header: &'a str, key: &str) -> Option<&'a str> {
    let at = header
        .find(&format!("'{key}'"))
        .or_else(|| header.find(&format!("\"{key}\"")))?;
    let rest = header[at + key.len() + 2..].trim_start();
    let rest = rest.strip_prefix(':')?.trim_start();
    let mut depth = 0i32;
    for (i, c) in rest.char_indices() {
        match c {
            '(' => depth += 1,
            ')' => depth -= 1,
            ',' | '}' if depth == 0 => return Some(rest[..i].trim()),
            _ => {}
        }
    }
    Some(rest.trim())
}

/// (little endian, kind `f`/`i`/`u`, element size) of a dtype string such as `<f8`.
fn parse_descr(d: &str) -> Result<(bool, char, usize), String> {
    let mut chars = d.chars();
    let order = chars.next().ok_or("empty .npy 'descr'")?;
    let little = match order {
        '<' | '|' | '=' => true,
        '>' => false,
        _ => return Err(format!(".npy dtype {d:?} is not supported")),
    };
    let kind = chars.next().ok_or("short .npy 'descr'")?;
    let size: usize = chars
        .as_str()
        .parse()
        .map_err(|_| format!(".npy dtype {d:?} is not supported"))?;
    match (kind, size) {
        ('f', 4 | 8) | ('i' | 'u', 1 | 2 | 4 | 8) => Ok((little, kind, size)),
        _ => Err(format!(
            ".npy dtype {d:?} is not supported (float or integer arrays only)"
        )),
    }
}

fn element(c: &[u8], little: bool, kind: char) -> f64 {
    let mut b = [0u8; 8];
    if little {
        b[..c.len()].copy_from_slice(c);
    } else {
        for (i, &x) in c.iter().rev().enumerate() {
            b[i] = x;
        }
    }
    let bits = u64::from_le_bytes(b);
    match (kind, c.len()) {
        ('f', 8) => f64::from_bits(bits),
        ('f', _) => f32::from_bits(bits as u32) as f64,
        ('i', n) => {
            let shift = 64 - 8 * n as u32;
            ((bits << shift) as i64 >> shift) as f64
        }
        _ => bits as f64,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_is_numpys() {
        // The bytes of `np.save(buf, np.zeros(2174))`'s header (numpy 2, version 1.0).
        let b = write_npy(&[2174], &vec![0.0; 2174]);
        let header = std::str::from_utf8(&b[10..128]).unwrap();
        assert!(header.starts_with("{'descr': '<f8', 'fortran_order': False, 'shape': (2174,), }"));
        assert!(header.ends_with(" \n"));
        assert_eq!(u16::from_le_bytes([b[8], b[9]]), 118);
        assert_eq!(b.len(), 128 + 8 * 2174);
    }

    #[test]
    fn round_trips_and_reads_other_dtypes() {
        let b = write_npy(&[0], &[]);
        assert_eq!(read_npy(&b).unwrap().shape, vec![0]);
        let mut be = b"\x93NUMPY\x01\x00".to_vec();
        let h = "{'descr': '>i4', 'fortran_order': False, 'shape': (2,), }\n";
        be.extend_from_slice(&(h.len() as u16).to_le_bytes());
        be.extend_from_slice(h.as_bytes());
        be.extend_from_slice(&(-3i32).to_be_bytes());
        be.extend_from_slice(&7i32.to_be_bytes());
        assert_eq!(read_npy(&be).unwrap().data, vec![-3.0, 7.0]);
    }

    #[test]
    fn short_or_hostile_arrays_are_errors() {
        let b = write_npy(&[4], &[1.0, 2.0, 3.0, 4.0]);
        assert!(read_npy(&b[..b.len() - 1]).is_err());
        assert!(read_npy(b"\x93NUMPY\x01\x00\xff\xff").is_err());
        let mut huge = b"\x93NUMPY\x01\x00".to_vec();
        let h =
            "{'descr': '<f8', 'fortran_order': False, 'shape': (99999999999999, 99999999999), }\n";
        huge.extend_from_slice(&(h.len() as u16).to_le_bytes());
        huge.extend_from_slice(h.as_bytes());
        assert!(read_npy(&huge).is_err());
        assert!(read_npy(b"PK\x03\x04").is_err());
    }
}
