//! ROS 2 CDR: the 4-byte encapsulation header, then a plain CDR body in the byte order it names.
//!
//! `cdr-encoding` does the body (alignment is counted from the first byte after the header, as ROS 2
//! does, and padding bytes are skipped without looking at their values); this file only reads and
//! writes the header, which that crate leaves to its caller.

use byteorder::{BigEndian, LittleEndian};
use serde::de::DeserializeOwned;
use serde::Serialize;

/// Representation identifier of plain CDR, big-endian (`CDR_BE`).
const CDR_BE: [u8; 2] = [0x00, 0x00];
/// Representation identifier of plain CDR, little-endian (`CDR_LE`), what ROS 2 writes on x86 and ARM.
const CDR_LE: [u8; 2] = [0x00, 0x01];

/// Decodes one ROS 2 message: checks the encapsulation header (`00 00` big-endian or `00 01`
/// little-endian; the two options bytes are ignored) and deserializes the body. Bytes after the
/// message (alignment padding at the end) are ignored.
pub fn decode<T: DeserializeOwned>(data: &[u8]) -> Result<T, String> {
    if data.len() < 4 {
        return Err(format!(
            "{} bytes, shorter than the 4-byte CDR encapsulation header",
            data.len()
        ));
    }
    let (header, body) = data.split_at(4);
    let result = match [header[0], header[1]] {
        CDR_LE => cdr_encoding::from_bytes::<T, LittleEndian>(body),
        CDR_BE => cdr_encoding::from_bytes::<T, BigEndian>(body),
        other => {
            return Err(format!(
                "encapsulation {:02x} {:02x} is not plain CDR (00 00 or 00 01); XCDR2 and parameter lists are not supported",
                other[0], other[1]
            ))
        }
    };
    result
        .map(|(msg, _consumed)| msg)
        .map_err(|e| format!("CDR body: {e}"))
}

/// Encodes `msg` as ROS 2 writes it: header `00 01 00 00`, then a little-endian plain CDR body.
///
/// # Panics
/// Only when `T` holds something plain CDR cannot represent (a map of unknown length); never for the
/// message structs of [`crate::decode::ros2_msgs`].
pub fn encode_le<T: Serialize>(msg: &T) -> Vec<u8> {
    let mut out = vec![CDR_LE[0], CDR_LE[1], 0x00, 0x00];
    // Writing into a Vec cannot fail; the serializer only rejects types CDR has no layout for.
    cdr_encoding::to_writer::<T, LittleEndian, _>(&mut out, msg)
        .expect("type has a plain CDR layout");
    out
}

/// Encodes `msg` with header `00 00 00 00` and a big-endian body (tests and tools that need to
/// produce what a big-endian machine would record).
///
/// # Panics
/// As [`encode_le`].
pub fn encode_be<T: Serialize>(msg: &T) -> Vec<u8> {
    let mut out = vec![CDR_BE[0], CDR_BE[1], 0x00, 0x00];
    cdr_encoding::to_writer::<T, BigEndian, _>(&mut out, msg).expect("type has a plain CDR layout");
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::decode::ros2_msgs::{Header, Point, PointStamped, Time};

    fn sample() -> PointStamped {
        PointStamped {
            header: Header {
                stamp: Time {
                    sec: 1_718_460_000,
                    nanosec: 123_456_789,
                },
                frame_id: "map".into(),
            },
            point: Point {
                x: 1.5,
                y: -2.25,
                z: 3.0,
            },
        }
    }

    #[test]
    fn round_trips_both_byte_orders() {
        let m = sample();
        assert_eq!(decode::<PointStamped>(&encode_le(&m)).unwrap(), m);
        assert_eq!(decode::<PointStamped>(&encode_be(&m)).unwrap(), m);
        assert_ne!(encode_le(&m), encode_be(&m));
    }

    #[test]
    fn header_layout() {
        let le = encode_le(&sample());
        assert_eq!(&le[..4], &[0, 1, 0, 0]);
        // sec (4) nanosec (4) frame_id len (4) "map\0" (4) then 8-aligned doubles: no padding.
        assert_eq!(le.len(), 4 + 16 + 24);
        assert_eq!(&le[4..8], &1_718_460_000i32.to_le_bytes());
    }

    #[test]
    fn padding_values_and_options_are_ignored() {
        let mut m = sample();
        m.header.frame_id = "odom".into(); // len 5 with NUL: 3 padding bytes before the doubles
        let mut bytes = encode_le(&m);
        bytes[2] = 0xAB;
        bytes[3] = 0xCD;
        let pad_start = 4 + 4 + 4 + 4 + 5;
        for b in &mut bytes[pad_start..pad_start + 3] {
            *b = 0xEE;
        }
        assert_eq!(decode::<PointStamped>(&bytes).unwrap(), m);
    }

    #[test]
    fn rejects_bad_input_without_panicking() {
        assert!(decode::<PointStamped>(&[]).is_err());
        assert!(decode::<PointStamped>(&[0, 1, 0]).is_err());
        assert!(decode::<PointStamped>(&[0, 7, 0, 0, 1, 2, 3]).is_err());
        let bytes = encode_le(&sample());
        for cut in 4..bytes.len() {
            assert!(decode::<PointStamped>(&bytes[..cut]).is_err(), "cut {cut}");
        }
        // A string length far past the end.
        let mut bad = bytes.clone();
        bad[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(decode::<PointStamped>(&bad).is_err());
    }
}
