//! Where a message keeps its stamps, for copies that move them (`eval --annotate`'s aligned channel,
//! `trajdrift restamp`): a leading `std_msgs/Header` (every stamped message), or the header of each
//! transform of a TF batch (`tf2_msgs/TFMessage`). Stamps are rewritten in place, in the message's
//! own encoding (ROS 1, or plain CDR either endianness), so every other byte stays as it was.
//!
//! Whether a type is stamped is read from its schema's text: its first field is `Header header`
//! (`std_msgs/Header`, `std_msgs/msg/Header`). The trajectory types trajdrift reads all are.

use crate::decode::tf::is_tf_message;

pub use super::channels::{header_stamp, shift_stamp};

/// Where a channel's messages keep their stamps.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StampLayout {
    /// A leading `std_msgs/Header`.
    Header,
    /// A TF batch: one header per transform.
    TfBatch,
    /// No stamp inside the message: only its log and publish times say when.
    None,
}

/// The layout of a channel's messages from its schema's name and text.
pub fn layout_of(schema_name: &str, schema_text: &[u8]) -> StampLayout {
    if is_tf_message(schema_name) {
        return StampLayout::TfBatch;
    }
    if crate::decode::message_kind(schema_name).is_some() {
        return StampLayout::Header;
    }
    let text = String::from_utf8_lossy(schema_text);
    let first_field = text
        .lines()
        .map(|l| l.split('#').next().unwrap_or("").trim())
        .find(|l| !l.is_empty() && !l.contains('='));
    match first_field.map(|l| l.split_whitespace().collect::<Vec<_>>()) {
        Some(words)
            if words.len() >= 2
                && matches!(
                    words[0],
                    "Header" | "std_msgs/Header" | "std_msgs/msg/Header"
                ) =>
        {
            StampLayout::Header
        }
        _ => StampLayout::None,
    }
}

/// Byte order of a message's numbers.
#[derive(Clone, Copy)]
enum Order {
    Little,
    Big,
}

fn u32_at(data: &[u8], at: usize, order: Order) -> Result<u32, String> {
    let b: [u8; 4] = data
        .get(at..at + 4)
        .and_then(|s| s.try_into().ok())
        .ok_or_else(|| format!("{} bytes end before byte {}", data.len(), at + 4))?;
    Ok(match order {
        Order::Little => u32::from_le_bytes(b),
        Order::Big => u32::from_be_bytes(b),
    })
}

/// The offsets of each transform's stamp (its seconds; nanoseconds follow) in a TF batch, and the
/// encoding's byte order and whether seconds are signed (CDR) or not (ROS 1).
fn tf_stamp_offsets(encoding: &str, data: &[u8]) -> Result<(Vec<usize>, Order, bool), String> {
    let (order, base, cdr) = match encoding {
        "ros1" => (Order::Little, 0usize, false),
        "cdr" => match data.get(..2) {
            Some([0, 1]) => (Order::Little, 4, true),
            Some([0, 0]) => (Order::Big, 4, true),
            _ => return Err("not plain CDR".into()),
        },
        other => return Err(format!("message encoding `{other}`")),
    };
    // CDR aligns each primitive to its size, counted from the payload's start.
    let align = |at: usize, n: usize| {
        if cdr {
            base + (at - base).div_ceil(n) * n
        } else {
            at
        }
    };
    let mut at = align(base, 4);
    let count = u32_at(data, at, order)? as usize;
    at += 4;
    // A transform takes at least 60 bytes: refuse counts the bytes cannot hold before allocating.
    if count > data.len() / 60 + 1 {
        return Err(format!("{count} transforms in {} bytes", data.len()));
    }
    let mut out = Vec::with_capacity(count);
    for _ in 0..count {
        if !cdr {
            at += 4; // ROS 1 header: uint32 seq
        }
        at = align(at, 4);
        out.push(at);
        at += 8;
        for _ in 0..2 {
            // frame_id, child_frame_id
            at = align(at, 4);
            let len = u32_at(data, at, order)? as usize;
            at = at
                .checked_add(4 + len)
                .filter(|&e| e <= data.len())
                .ok_or_else(|| format!("a frame name of {len} bytes runs past the message"))?;
        }
        at = align(at, 8) + 7 * 8;
        if at > data.len() {
            return Err(format!("{} bytes end inside a transform", data.len()));
        }
    }
    Ok((out, order, cdr))
}

/// A TF batch with each transform's stamp mapped by `map` (ns → ns), in a copy; `map` returning
/// `None` leaves that stamp as it was.
pub fn map_tf_stamps(
    encoding: &str,
    data: &[u8],
    map: &mut dyn FnMut(i64) -> Option<i64>,
) -> Result<Vec<u8>, String> {
    let (offsets, order, signed) = tf_stamp_offsets(encoding, data)?;
    let mut out = data.to_vec();
    for at in offsets {
        let sec = u32_at(data, at, order)?;
        let nsec = u32_at(data, at + 4, order)?;
        let sec = if signed {
            i64::from(sec as i32)
        } else {
            i64::from(sec)
        };
        let ns = sec * 1_000_000_000 + i64::from(nsec);
        let Some(new) = map(ns) else { continue };
        let (s, n) = (
            new.div_euclid(1_000_000_000),
            new.rem_euclid(1_000_000_000) as u32,
        );
        let s: u32 = if signed {
            i32::try_from(s)
                .map_err(|_| format!("stamp {new} ns out of the int32 seconds range"))?
                as u32
        } else {
            u32::try_from(s)
                .map_err(|_| format!("stamp {new} ns out of the uint32 seconds range"))?
        };
        let (sb, nb) = match order {
            Order::Little => (s.to_le_bytes(), n.to_le_bytes()),
            Order::Big => (s.to_be_bytes(), n.to_be_bytes()),
        };
        out[at..at + 4].copy_from_slice(&sb);
        out[at + 4..at + 8].copy_from_slice(&nb);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::decode::ros2_msgs::{TFMessage, Time, TransformStamped};
    use crate::decode::tf::decode_tf_message;
    use crate::decode::{cdr, ros1, Encoding};

    fn batch() -> TFMessage {
        let mut a = TransformStamped::default();
        a.header.frame_id = "odom".into();
        a.header.stamp = Time::from_ns(1_000_000_123);
        a.child_frame_id = "base_link".into();
        a.transform.translation.x = 2.5;
        let mut b = a.clone();
        b.header.frame_id = "map_x".into();
        b.child_frame_id = "o".into();
        b.header.stamp = Time::from_ns(7_999_999_999);
        TFMessage {
            transforms: vec![a, b],
        }
    }

    #[test]
    fn every_transform_stamp_moves_and_nothing_else() {
        let m = batch();
        for (enc, name, data) in [
            (Encoding::Cdr, "cdr", cdr::encode_le(&m)),
            (Encoding::Ros1, "ros1", ros1::encode_tf_message(4, &m)),
        ] {
            let out = map_tf_stamps(name, &data, &mut |t| Some(t + 1_500_000_000)).unwrap();
            let (before, after) = (
                decode_tf_message(enc, &data).unwrap(),
                decode_tf_message(enc, &out).unwrap(),
            );
            for (x, y) in before.iter().zip(&after) {
                assert_eq!(y.stamp_ns, x.stamp_ns + 1_500_000_000);
                assert_eq!(
                    (&x.parent, &x.child, x.translation),
                    (&y.parent, &y.child, y.translation)
                );
            }
            let back = map_tf_stamps(name, &out, &mut |t| Some(t - 1_500_000_000)).unwrap();
            assert_eq!(back, data);
            assert!(map_tf_stamps(name, &data[..data.len() - 3], &mut |t| Some(t)).is_err());
        }
    }

    #[test]
    fn stamped_types_are_read_from_their_schema() {
        assert_eq!(layout_of("nav_msgs/msg/Odometry", b""), StampLayout::Header);
        assert_eq!(layout_of("tf2_msgs/TFMessage", b""), StampLayout::TfBatch);
        let imu = b"# comment\nstd_msgs/Header header\nfloat64 x\n";
        assert_eq!(layout_of("sensor_msgs/msg/Imu", imu), StampLayout::Header);
        let ros1 = b"uint8 CONST=3\nHeader header\n";
        assert_eq!(
            layout_of("sensor_msgs/PointCloud2", ros1),
            StampLayout::Header
        );
        assert_eq!(
            layout_of("std_msgs/String", b"string data\n"),
            StampLayout::None
        );
    }
}
