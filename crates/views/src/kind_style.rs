//! How each toolpath segment kind is drawn: its marker namespace, colour and line width.

use cell_msgs::std_msgs::ColorRGBA;
use cell_msgs::ToolpathSegment;

/// Marker namespace, colour and line width of one segment kind.
#[derive(Debug, Clone, PartialEq)]
pub struct KindStyle {
    /// Marker namespace: `cut`, `travel`, `deposit`, `lead`, or `kind_<n>` for an unknown kind.
    pub namespace: String,
    /// Line colour.
    pub color: ColorRGBA,
    /// Line width (m).
    pub width_m: f64,
}

const fn rgba(r: f32, g: f32, b: f32, a: f32) -> ColorRGBA {
    ColorRGBA { r, g, b, a }
}

/// Cuts: red, 1 mm.
pub const CUT: ColorRGBA = rgba(0.86, 0.16, 0.16, 1.0);
/// Travel (rapids): grey, half transparent, 0.5 mm.
pub const TRAVEL: ColorRGBA = rgba(0.6, 0.6, 0.6, 0.5);
/// Deposits (WAAM beads, extrusion): orange, 1.5 mm.
pub const DEPOSIT: ColorRGBA = rgba(1.0, 0.55, 0.0, 1.0);
/// Leads in and out: blue, 1 mm.
pub const LEAD: ColorRGBA = rgba(0.12, 0.44, 0.82, 1.0);
/// A kind this build does not know: magenta, 1 mm.
pub const UNKNOWN: ColorRGBA = rgba(0.9, 0.0, 0.9, 1.0);

/// The style of `ToolpathSegment.kind`.
pub fn kind_style(kind: u8) -> KindStyle {
    let (namespace, color, width_m) = match kind {
        ToolpathSegment::KIND_CUT => ("cut".to_owned(), CUT, 0.001),
        ToolpathSegment::KIND_TRAVEL => ("travel".to_owned(), TRAVEL, 0.0005),
        ToolpathSegment::KIND_DEPOSIT => ("deposit".to_owned(), DEPOSIT, 0.0015),
        ToolpathSegment::KIND_LEAD => ("lead".to_owned(), LEAD, 0.001),
        other => (format!("kind_{other}"), UNKNOWN, 0.001),
    };
    KindStyle {
        namespace,
        color,
        width_m,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_kind_has_its_own_namespace_and_colour() {
        let kinds = [
            ToolpathSegment::KIND_CUT,
            ToolpathSegment::KIND_TRAVEL,
            ToolpathSegment::KIND_DEPOSIT,
            ToolpathSegment::KIND_LEAD,
            9,
        ];
        let styles: Vec<KindStyle> = kinds.iter().map(|&k| kind_style(k)).collect();
        for (i, a) in styles.iter().enumerate() {
            for b in &styles[i + 1..] {
                assert_ne!(a.namespace, b.namespace);
                assert_ne!(a.color, b.color);
            }
        }
        assert_eq!(styles[4].namespace, "kind_9");
    }
}
