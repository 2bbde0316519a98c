//! File names of configuration labels.

/// A file-name-safe slug of a label: ASCII letters and digits lower-cased, every other
/// character `-` (so `"IS-STORM (trajectory)"` becomes `is-storm--trajectory-`).
pub fn slug(label: &str) -> String {
    label
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() {
                c.to_ascii_lowercase()
            } else {
                '-'
            }
        })
        .collect()
}
