//! ROS 2 serialized messages: a 4-byte encapsulation header followed by a plain (XCDR1) CDR body.
//!
//! The body is written by `cdr_encoding`, which aligns each primitive to its size counted from
//! the start of the body (after the header), as ROS 2 requires.

use byteorder::{BigEndian, LittleEndian};
use serde::{de::DeserializeOwned, Serialize};

/// Encapsulation header of little-endian plain CDR (`CDR_LE`), as ROS 2 writes it.
pub const CDR_LE_HEADER: [u8; 4] = [0x00, 0x01, 0x00, 0x00];

/// Most bytes that may follow a message: ROS 2 pads serialized data to a multiple of 4.
pub const MAX_PADDING: usize = 3;

/// Byte order of a CDR body, taken from its encapsulation header.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Endianness {
    /// `CDR_BE` (representation id 0x0000).
    Big,
    /// `CDR_LE` (representation id 0x0001).
    Little,
}

/// Why a serialized message could not be written or read.
#[derive(Debug, thiserror::Error)]
pub enum CdrError {
    /// Fewer bytes than the encapsulation header.
    #[error("serialized message has {0} bytes, less than the 4-byte encapsulation header")]
    TooShort(usize),
    /// The representation id is not plain CDR (e.g. XCDR2 or a parameter list).
    #[error("unsupported encapsulation {0:#06x}: expected CDR_BE (0x0000) or CDR_LE (0x0001)")]
    Encapsulation(u16),
    /// The body does not match the type (too short, bad bool or UTF-8, ...).
    #[error("CDR body: {0}")]
    Body(#[from] cdr_encoding::Error),
    /// Bytes left after the message beyond alignment padding.
    #[error("{0} bytes left after the message (at most {MAX_PADDING} padding bytes are allowed)")]
    Trailing(usize),
}

/// Splits a serialized message into its byte order and body.
pub fn split_header(bytes: &[u8]) -> Result<(Endianness, &[u8]), CdrError> {
    let (header, body) = bytes
        .split_first_chunk::<4>()
        .ok_or(CdrError::TooShort(bytes.len()))?;
    // Bytes 2..4 are options (padding count); they do not change how the body is read.
    match u16::from_be_bytes([header[0], header[1]]) {
        0x0000 => Ok((Endianness::Big, body)),
        0x0001 => Ok((Endianness::Little, body)),
        other => Err(CdrError::Encapsulation(other)),
    }
}

/// Fails if more than [`MAX_PADDING`] bytes follow a message body.
pub(crate) fn check_trailing(left: usize) -> Result<(), CdrError> {
    if left > MAX_PADDING {
        return Err(CdrError::Trailing(left));
    }
    Ok(())
}

/// Serializes a message as ROS 2 does: [`CDR_LE_HEADER`] then the little-endian CDR body.
pub fn to_cdr<T: Serialize>(value: &T) -> Result<Vec<u8>, CdrError> {
    let body = cdr_encoding::to_vec::<T, LittleEndian>(value)?;
    Ok([CDR_LE_HEADER.as_slice(), &body].concat())
}

/// Deserializes a ROS 2 serialized message (`CDR_LE` or `CDR_BE`). Errors, never panics, on
/// short or malformed input.
pub fn from_cdr<T: DeserializeOwned>(bytes: &[u8]) -> Result<T, CdrError> {
    let (endianness, body) = split_header(bytes)?;
    let (value, used) = match endianness {
        Endianness::Little => cdr_encoding::from_bytes::<T, LittleEndian>(body)?,
        Endianness::Big => cdr_encoding::from_bytes::<T, BigEndian>(body)?,
    };
    check_trailing(body.len().saturating_sub(used))?;
    Ok(value)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{
        builtin_interfaces::Time, geometry_msgs::Point, std_msgs::Header, ToolpathSegment,
    };

    #[test]
    fn known_layout_with_alignment_after_header() {
        // uint8 kind, pad to 4, uint32 layer, sequence of Point (f64s aligned to 8 in the body).
        let seg = ToolpathSegment {
            kind: 3,
            layer: 7,
            points: vec![Point {
                x: 1.0,
                y: 2.0,
                z: 3.0,
            }],
            ..Default::default()
        };
        let bytes = to_cdr(&seg).expect("serializes");
        let mut want = CDR_LE_HEADER.to_vec();
        want.extend([3, 0, 0, 0, 7, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0]); // kind, layer, len=1, pad to 16
        for v in [1.0f64, 2.0, 3.0] {
            want.extend(v.to_le_bytes());
        }
        for _ in 0..6 {
            want.extend([0, 0, 0, 0]); // six empty sequences
        }
        assert_eq!(bytes, want);
    }

    #[test]
    fn round_trip_and_big_endian() {
        let header = Header {
            stamp: Time {
                sec: -3,
                nanosec: 500,
            },
            frame_id: "map".into(),
        };
        let bytes = to_cdr(&header).expect("serializes");
        assert_eq!(from_cdr::<Header>(&bytes).expect("decodes"), header);

        let mut be = vec![0, 0, 0, 0];
        be.extend(cdr_encoding::to_vec::<Header, BigEndian>(&header).expect("serializes"));
        assert_eq!(from_cdr::<Header>(&be).expect("decodes"), header);
    }

    #[test]
    fn garbage_is_an_error_not_a_panic() {
        let header = Header {
            stamp: Time { sec: 1, nanosec: 2 },
            frame_id: "frame".into(),
        };
        let bytes = to_cdr(&header).expect("serializes");
        for n in 0..bytes.len() {
            assert!(from_cdr::<Header>(&bytes[..n]).is_err(), "truncated to {n}");
        }
        let mut long = bytes.clone();
        long.extend([0; 3]);
        assert!(
            from_cdr::<Header>(&long).is_ok(),
            "3 padding bytes are fine"
        );
        long.push(0);
        assert!(matches!(
            from_cdr::<Header>(&long),
            Err(CdrError::Trailing(4))
        ));
        assert!(matches!(
            from_cdr::<Header>(&[0, 7, 0, 0]),
            Err(CdrError::Encapsulation(7))
        ));
        // Every single-byte corruption either decodes or errors.
        for i in 0..bytes.len() {
            for v in [0x00, 0x7f, 0xff] {
                let mut bad = bytes.clone();
                bad[i] = v;
                let _ = from_cdr::<Header>(&bad);
            }
        }
    }
}
