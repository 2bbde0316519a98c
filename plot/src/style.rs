//! One fixed colour, marker and line style per algorithm (Okabe–Ito, colour-blind-safe).

use super::*;

/// A point marker.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Marker {
    /// Circle.
    Circle,
    /// Square.
    Square,
    /// Upward triangle.
    Triangle,
    /// Downward triangle.
    TriangleDown,
    /// Diamond.
    Diamond,
    /// Plus sign.
    Plus,
    /// Diagonal cross.
    Cross,
    /// No marker (reference lines).
    None,
}

/// How a series is drawn, the same in every figure: a colour, a marker (filled or hollow) and a
/// line pattern.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Style {
    /// Line, marker and band colour.
    pub color: RGBColor,
    /// Marker at each point.
    pub marker: Marker,
    /// Filled marker (`false`: outline only).
    pub filled: bool,
    /// Dashed line (variants of an algorithm, reference lines).
    pub dashed: bool,
}

/// The style of a series, a function of its label alone, so an algorithm looks the same in every
/// figure whatever else the figure shows. Variants of an algorithm (DAgger (minibatch), the
/// episodic-objective control, the IS-STORM pair) share their family's colour and differ by
/// marker and a dashed line; reference policies and reference lines are grey and dashed, without
/// markers; a label not listed gets a colour and marker derived from a hash of its text.
pub fn style_for(label: &str) -> Style {
    use okabe_ito::*;
    let s = |color, marker, filled, dashed| Style {
        color,
        marker,
        filled,
        dashed,
    };
    let grey = |v: u8| s(RGBColor(v, v, v), Marker::None, false, true);
    match label {
        "BC" => s(BLACK, Marker::Circle, false, false),
        "DAgger" => s(ORANGE, Marker::Square, true, false),
        "DAgger (minibatch)" => s(ORANGE, Marker::Square, false, true),
        "SGD" => s(SKY_BLUE, Marker::TriangleDown, true, false),
        "Adam" => s(BLUE, Marker::Diamond, true, false),
        "Adam (episodic objective)" => s(BLUE, Marker::Diamond, false, true),
        "RMSProp" => s(BLUISH_GREEN, Marker::Triangle, true, false),
        "STORM" => s(VERMILLION, Marker::Circle, true, false),
        "IS-STORM (trajectory)" => s(REDDISH_PURPLE, Marker::Cross, true, false),
        "IS-STORM (per-decision)" => s(REDDISH_PURPLE, Marker::Plus, true, true),
        "SGD + baseline" => s(SKY_BLUE, Marker::TriangleDown, false, true),
        "STORM + baseline" => s(VERMILLION, Marker::Circle, false, true),
        "IS-STORM + baseline" => s(DARK_YELLOW, Marker::Square, false, true),
        // Fig. 4.2's estimates.
        "RMSE (95% CI)" | "vs reference (95% CI)" => s(BLUE, Marker::Circle, true, false),
        "− ref. variance (95% CI)" => s(VERMILLION, Marker::Square, true, false),
        l if l.starts_with("Expert") || l.starts_with("σ") => grey(0),
        l if l.starts_with("Straight to goal") || l.starts_with("reference SE") => grey(130),
        other => {
            const COLORS: [RGBColor; 7] = [
                ORANGE,
                SKY_BLUE,
                BLUISH_GREEN,
                DARK_YELLOW,
                BLUE,
                VERMILLION,
                REDDISH_PURPLE,
            ];
            const MARKERS: [Marker; 7] = [
                Marker::Circle,
                Marker::Square,
                Marker::Triangle,
                Marker::TriangleDown,
                Marker::Diamond,
                Marker::Plus,
                Marker::Cross,
            ];
            let h = ilopt::seeding::fnv1a(other);
            s(
                COLORS[(h % 7) as usize],
                MARKERS[((h / 7) % 7) as usize],
                true,
                false,
            )
        }
    }
}

/// The style of the `k`-th of several runs drawn together (counting from 0), fixed by its
/// position alone so that a run keeps its colour when the runs after it change: the Okabe–Ito
/// colours in a fixed order with a marker each; from the ninth on the colours repeat with the
/// next marker and a dashed line.
pub fn by_position(k: usize) -> Style {
    use okabe_ito::*;
    const COLORS: [RGBColor; 8] = [
        BLUE,
        VERMILLION,
        BLUISH_GREEN,
        ORANGE,
        REDDISH_PURPLE,
        SKY_BLUE,
        DARK_YELLOW,
        BLACK,
    ];
    const MARKERS: [Marker; 7] = [
        Marker::Circle,
        Marker::Square,
        Marker::Triangle,
        Marker::Diamond,
        Marker::TriangleDown,
        Marker::Cross,
        Marker::Plus,
    ];
    let round = k / COLORS.len();
    Style {
        color: COLORS[k % COLORS.len()],
        marker: MARKERS[(k + round) % MARKERS.len()],
        filled: round.is_multiple_of(2),
        dashed: round > 0,
    }
}
