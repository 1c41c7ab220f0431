//! A `HeatMap` as a `sensor_msgs/Image` in `32FC1`.

use cell_msgs::sensor_msgs::Image;
use cell_msgs::std_msgs::Header;
use cell_msgs::HeatMap;

use crate::{frames, ViewError};

/// The `sensor_msgs/Image` encoding of one 32-bit float per pixel (`image_encodings.hpp`).
pub const ENCODING_32FC1: &str = "32FC1";

/// Bytes per `32FC1` pixel.
const PIXEL_BYTES: u32 = 4;

/// The heat map as a `32FC1` image: `width` × `height` pixels, the values unchanged (in the
/// heat map's `unit`; NaN stays NaN), little-endian (`is_bigendian` 0), row-major with
/// `step = 4 * width` bytes per row. Image row r is heat-map row r, so row 0 (at the heat map's
/// origin) is the image's top row. Frame and stamp are the heat map's ([`frames::of_header`]).
///
/// # Errors
/// [`ViewError::HeatMap`] when `data` is not `width * height` values, or a row would be more
/// than `u32::MAX` bytes.
pub fn heat_map_image(heat_map: &HeatMap) -> Result<Image, ViewError> {
    let error = |reason: String| ViewError::HeatMap {
        quantity: heat_map.quantity.clone(),
        reason,
    };
    let cells = u64::from(heat_map.width) * u64::from(heat_map.height);
    if cells != heat_map.data.len() as u64 {
        return Err(error(format!(
            "{}x{} cells need {cells} values, got {}",
            heat_map.width,
            heat_map.height,
            heat_map.data.len()
        )));
    }
    let step = heat_map.width.checked_mul(PIXEL_BYTES).ok_or_else(|| {
        error(format!(
            "{} columns are too wide for an image row",
            heat_map.width
        ))
    })?;
    let data = heat_map.data.iter().flat_map(|v| v.to_le_bytes()).collect();
    Ok(Image {
        header: Header {
            stamp: heat_map.header.stamp,
            frame_id: frames::of_header(&heat_map.header),
        },
        height: heat_map.height,
        width: heat_map.width,
        encoding: ENCODING_32FC1.to_owned(),
        is_bigendian: 0,
        step,
        data,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_become_little_endian_rows() {
        let mut hm = HeatMap::new(
            "sheet_temperature",
            "K",
            3,
            2,
            vec![
                293.15,
                300.0,
                -1.5, //
                f32::NAN,
                0.0,
                1e6,
            ],
        )
        .expect("3x2");
        hm.header.frame_id = "sheet".into();
        let image = heat_map_image(&hm).expect("valid");
        assert_eq!((image.width, image.height, image.step), (3, 2, 12));
        assert_eq!(image.encoding, "32FC1");
        assert_eq!(image.is_bigendian, 0);
        assert_eq!(image.header.frame_id, "sheet");
        assert_eq!(image.data.len(), 24);
        let pixel = |row: usize, col: usize| {
            let at = row * image.step as usize + col * 4;
            f32::from_le_bytes(image.data[at..at + 4].try_into().expect("4 bytes"))
        };
        assert_eq!(pixel(0, 0), 293.15);
        assert_eq!(pixel(0, 2), -1.5);
        assert!(pixel(1, 0).is_nan());
        assert_eq!(pixel(1, 2), 1e6);
        assert_eq!(
            &image.data[4..8],
            &[0x00, 0x00, 0x96, 0x43],
            "300.0f32 little-endian"
        );
    }

    #[test]
    fn a_short_heat_map_is_refused() {
        let mut hm = HeatMap::new("wire_exposure", "1", 2, 2, vec![0.0; 4]).expect("2x2");
        hm.data.pop();
        let e = heat_map_image(&hm).unwrap_err();
        assert_eq!(
            e.to_string(),
            "heat map \"wire_exposure\": 2x2 cells need 4 values, got 3"
        );
    }
}
