//! Length units named in file headers, converted to metres.

/// Metres per unit for a length-unit word (`m`, `mm`, `um`, `µm`, `micrometer`, `nm`, `Å`, ...),
/// case-insensitive for the spelled-out names.
pub fn metres_per_unit(word: &str) -> Option<f64> {
    let w = word.trim();
    let factor = match w {
        "m" => 1.0,
        "cm" => 1e-2,
        "mm" => 1e-3,
        "um" | "µm" | "μm" => 1e-6,
        "nm" => 1e-9,
        "pm" => 1e-12,
        "Å" | "A" => 1e-10,
        _ => match w.to_ascii_lowercase().as_str() {
            "meter" | "meters" | "metre" | "metres" => 1.0,
            "millimeter" | "millimeters" | "millimetre" | "millimetres" => 1e-3,
            "micrometer" | "micrometers" | "micrometre" | "micrometres" | "micron" | "microns" => {
                1e-6
            }
            "nanometer" | "nanometers" | "nanometre" | "nanometres" => 1e-9,
            "angstrom" | "angstroms" => 1e-10,
            _ => return None,
        },
    };
    Some(factor)
}

/// The length unit named in a column header such as `x_m`, `height (nm)`, `Lateral um`,
/// `Raw Micrometer` or `z[µm]`: the last word (split at anything that is not a letter) that is a
/// unit. Returns the factor to metres and the word.
pub fn unit_in_header(name: &str) -> Option<(f64, String)> {
    name.split(|c: char| !(c.is_alphabetic()))
        .filter(|w| !w.is_empty())
        .rev()
        .find_map(|w| metres_per_unit(w).map(|f| (f, w.to_string())))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn headers() {
        assert_eq!(unit_in_header("x_m").unwrap().0, 1.0);
        assert_eq!(unit_in_header("height (nm)").unwrap().0, 1e-9);
        assert_eq!(unit_in_header("Lateral um").unwrap().0, 1e-6);
        assert_eq!(unit_in_header("Raw Micrometer").unwrap().0, 1e-6);
        assert_eq!(unit_in_header("z[µm]").unwrap().0, 1e-6);
        assert!(unit_in_header("height").is_none());
        assert!(unit_in_header("12.5").is_none());
    }
}
