//! Raw film scans: the image as RGB channels, its resolution, smoothing, the channel a
//! density is read in, and the paper (unstained) level.
//!
//! A raw flatbed scan of a pressure film is not a vendor rendering: the stain is a diluted
//! magenta-red on white paper, with scanner noise and speckle, pen labels and tape. What this
//! module offers (used by `asperity film` in density mode):
//!
//! - [`read_rgb`]: the image in the film frame (x right, y up), 0–255 per channel (16-bit images
//!   keep their precision); its size is checked against [`crate::core::limits::MAX_IMAGE_PIXELS`] and
//!   the available memory **before** it is decoded. An EXIF/TIFF `Orientation` is applied: the
//!   film frame is the image as a viewer displays it.
//! - [`resolution`]: the pixel size the image declares: PNG `pHYs` (pixels per metre), TIFF
//!   `XResolution`/`YResolution` with `ResolutionUnit` (inch or cm), JPEG JFIF density (dots
//!   per inch or cm). Non-square pixels are refused.
//! - [`Channel`]: the optical density `D = log10(255 / v)` is read in luma (Rec. 709), in one
//!   of R, G, B, or in the *complementary* channel of the stain: the channel in which the
//!   stain colour is darkest (green for Prescale's magenta-red), where its density contrast is
//!   largest (luma dilutes it with the red channel, in which the stain hardly absorbs).
//! - [`smooth`]: a Gaussian filter of standard deviation σ pixels on every channel (separable,
//!   truncated at 3σ, mirrored at the border), against speckle that fragments the patches.
//! - [`paper_level`]: the density of the unstained background (paper, or the scanner lid where
//!   it dominates), as the mode of the density histogram (bins of 0.002), and its noise, from
//!   the half width at half maximum of the mode's peak on its low side (which stains cannot
//!   reach, and which a second, paler background does not widen): `σ = HWHM / 1.1774`.
//!   Densities above `mode + max(5σ, 0.01)` are stained; stained pixels below the first
//!   calibration point are *below range* (not unstained), and counted.

use crate::core::error::{num, Error, Result};
use ndarray::Array2;
use std::path::Path;

/// An RGB image in the film frame: `[[i, j]]` is column `i`, row `j` counted from the bottom;
/// values 0–255 (fractional for 16-bit images).
#[derive(Debug, Clone, PartialEq)]
pub struct RgbImage {
    /// Red channel, 0–255.
    pub r: Array2<f64>,
    /// Green channel, 0–255.
    pub g: Array2<f64>,
    /// Blue channel, 0–255.
    pub b: Array2<f64>,
}

impl RgbImage {
    /// Width and height in pixels.
    pub fn dim(&self) -> (usize, usize) {
        self.r.dim()
    }

    /// The colour of pixel `[[i, j]]`.
    pub fn rgb(&self, i: usize, j: usize) -> [f64; 3] {
        [self.r[[i, j]], self.g[[i, j]], self.b[[i, j]]]
    }

    /// Build from a closure giving the colour of (column, row from the top).
    pub fn from_fn(width: usize, height: usize, rgb_at: impl Fn(usize, usize) -> [f64; 3]) -> Self {
        let mut img = Self {
            r: Array2::zeros((width, height)),
            g: Array2::zeros((width, height)),
            b: Array2::zeros((width, height)),
        };
        for j in 0..height {
            let row = height - 1 - j;
            for i in 0..width {
                let [r, g, b] = rgb_at(i, row);
                img.r[[i, j]] = r;
                img.g[[i, j]] = g;
                img.b[[i, j]] = b;
            }
        }
        img
    }
}

/// Read a PNG, JPEG or TIFF image (8 or 16 bit) after checking its size against the limits.
pub fn read_rgb(path: &Path) -> Result<RgbImage> {
    if !path.exists() {
        return Err(Error::io(
            path,
            std::io::Error::new(std::io::ErrorKind::NotFound, "no such file"),
        ));
    }
    let reader = || -> Result<image::ImageReader<std::io::BufReader<std::fs::File>>> {
        image::ImageReader::open(path)
            .map_err(|e| Error::io(path, e))?
            .with_guessed_format()
            .map_err(|e| Error::io(path, e))
    };
    let (w, h) = reader()?
        .into_dimensions()
        .map_err(|e| Error::parse(path, 0, format!("cannot read image: {e}")))?;
    let pixels = w as u64 * h as u64;
    let name = path.display().to_string();
    if pixels > crate::core::limits::MAX_IMAGE_PIXELS {
        return Err(Error::limit(
            name,
            format!(
                "a {w} × {h} image has more than {} pixels",
                crate::core::limits::MAX_IMAGE_PIXELS
            ),
        ));
    }
    let budget = pixels.saturating_mul(crate::core::limits::FILM_BYTES_PER_PIXEL);
    crate::core::limits::check_memory(&name, budget, &format!("a {w} × {h} film image"))?;
    let mut r = reader()?;
    let mut limits = image::Limits::default();
    limits.max_alloc = Some(budget.max(1 << 20));
    r.limits(limits);
    let cannot = |e: image::ImageError| Error::parse(path, 0, format!("cannot read image: {e}"));
    let mut decoder = r.into_decoder().map_err(cannot)?;
    // The orientation a camera, phone or scanner app declares (EXIF / TIFF Orientation): the
    // film frame is the image as displayed, so the pixels are turned or mirrored as a viewer
    // shows them. Ignored, a scan tagged "rotate 90°" gave a film rotated against the one the
    // user sees, and nodes placed from the displayed image landed on other pixels.
    use image::ImageDecoder;
    let orientation = decoder.orientation().map_err(cannot)?;
    let mut img = image::DynamicImage::from_decoder(decoder).map_err(cannot)?;
    img.apply_orientation(orientation);
    let (w, h) = (img.width() as usize, img.height() as usize);
    if w == 0 || h == 0 {
        return Err(Error::parse(path, 0, "the image has no pixels"));
    }
    // 8-bit images keep their exact integer values; deeper images keep their precision.
    if img.color().bytes_per_pixel() / img.color().channel_count().max(1) <= 1 {
        let rgb = img.to_rgb8();
        Ok(RgbImage::from_fn(w, h, |c, r| {
            let p = rgb.get_pixel(c as u32, r as u32).0;
            [p[0] as f64, p[1] as f64, p[2] as f64]
        }))
    } else {
        let rgb = img.to_rgb32f();
        Ok(RgbImage::from_fn(w, h, |c, r| {
            let p = rgb.get_pixel(c as u32, r as u32).0;
            [
                p[0] as f64 * 255.0,
                p[1] as f64 * 255.0,
                p[2] as f64 * 255.0,
            ]
        }))
    }
}

/// The resolution an image declares.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Resolution {
    /// Dots per inch (square pixels).
    pub dpi: f64,
    /// Pixel size (m), from the unit the file uses (exact for pixels per metre).
    pub pixel_size_m: f64,
    /// Where it was read: `"PNG pHYs"`, `"TIFF XResolution"`, `"JPEG JFIF"`.
    pub source: &'static str,
}

impl Resolution {
    /// Pixel size in mm.
    pub fn pixel_size_mm(&self) -> f64 {
        self.pixel_size_m * 1e3
    }
}

/// Resolutions that image software declares by default (screen resolutions), not a scanner.
const SOFTWARE_DEFAULT_DPI: [f64; 2] = [72.0, 96.0];

/// Square pixels of `x`, `y` dots per `unit_m` metres; an error for non-square pixels or a
/// software-default resolution ([`SOFTWARE_DEFAULT_DPI`]).
fn square(
    path: &Path,
    x: f64,
    y: f64,
    unit_m: f64,
    source: &'static str,
) -> Result<Option<Resolution>> {
    if !(x.is_finite() && y.is_finite() && x > 0.0 && y > 0.0) {
        return Ok(None);
    }
    if (x - y).abs() > 1e-6 * x {
        return Err(Error::parse(
            path,
            0,
            format!(
                "the image declares non-square pixels ({} × {} dpi, {source}): give \
                 --pixel-size-mm or rescan with square pixels",
                num(x * 0.0254 / unit_m),
                num(y * 0.0254 / unit_m)
            ),
        ));
    }
    // 72 and 96 dpi are what image software writes when it does not know the resolution (the
    // screen defaults of Mac OS and Windows); a film scanned at one of them is rare, a film
    // rendered or re-saved by an application that wrote its default is common. Trusting it
    // would scale every length, area and load by the ratio to the true pixel size. Within
    // 1.5 %: the defaults rounded to pixels per metre (2835, 3780: 72.01, 96.01 dpi) or per
    // centimetre (28, 38: 71.12, 96.52 dpi); the nearest scanner resolution, 75 dpi, is 4 % away.
    let dpi = x * 0.0254 / unit_m;
    if let Some(default) = SOFTWARE_DEFAULT_DPI
        .into_iter()
        .find(|d| (dpi / d - 1.0).abs() < 0.015)
    {
        return Err(Error::parse(
            path,
            0,
            format!(
                "the image declares {} dpi ({source}), the default image software writes when \
                 the scan resolution is unknown: give --pixel-size-mm (for a true {default} dpi \
                 scan, {} mm)",
                num((dpi * 1e3).round() / 1e3),
                num((25.4 / default * 1e4).round() / 1e4)
            ),
        ));
    }
    Ok(Some(Resolution {
        dpi,
        pixel_size_m: unit_m / x,
        source,
    }))
}

fn png_resolution(path: &Path, b: &[u8]) -> Result<Option<Resolution>> {
    let mut k = 8;
    while k + 8 <= b.len() {
        let len = u32::from_be_bytes([b[k], b[k + 1], b[k + 2], b[k + 3]]) as usize;
        let kind = &b[k + 4..k + 8];
        if kind == b"pHYs" && k + 8 + 9 <= b.len() {
            let d = &b[k + 8..k + 17];
            let x = u32::from_be_bytes([d[0], d[1], d[2], d[3]]) as f64;
            let y = u32::from_be_bytes([d[4], d[5], d[6], d[7]]) as f64;
            // Unit 1: pixels per metre; 0: aspect ratio only.
            return if d[8] == 1 {
                square(path, x, y, 1.0, "PNG pHYs")
            } else {
                Ok(None)
            };
        }
        if kind == b"IDAT" || kind == b"IEND" {
            return Ok(None);
        }
        k += 12 + len;
    }
    Ok(None)
}

fn jpeg_resolution(path: &Path, b: &[u8]) -> Result<Option<Resolution>> {
    let mut k = 2;
    while k + 4 <= b.len() && b[k] == 0xFF {
        let marker = b[k + 1];
        let len = u16::from_be_bytes([b[k + 2], b[k + 3]]) as usize;
        if marker == 0xE0 && k + 4 + 12 <= b.len() && &b[k + 4..k + 9] == b"JFIF\0" {
            let d = &b[k + 9..];
            let units = d[2];
            let x = u16::from_be_bytes([d[3], d[4]]) as f64;
            let y = u16::from_be_bytes([d[5], d[6]]) as f64;
            return match units {
                1 => square(path, x, y, 0.0254, "JPEG JFIF"),
                2 => square(path, x, y, 0.01, "JPEG JFIF"),
                _ => Ok(None),
            };
        }
        if marker == 0xDA {
            break;
        }
        k += 2 + len;
    }
    Ok(None)
}

fn tiff_resolution(path: &Path, b: &[u8]) -> Result<Option<Resolution>> {
    let le = &b[..2] == b"II";
    let u16_at = |k: usize| -> Option<u16> {
        let s = b.get(k..k + 2)?;
        Some(if le {
            u16::from_le_bytes([s[0], s[1]])
        } else {
            u16::from_be_bytes([s[0], s[1]])
        })
    };
    let u32_at = |k: usize| -> Option<u32> {
        let s = b.get(k..k + 4)?;
        Some(if le {
            u32::from_le_bytes([s[0], s[1], s[2], s[3]])
        } else {
            u32::from_be_bytes([s[0], s[1], s[2], s[3]])
        })
    };
    let Some(ifd) = u32_at(4).map(|v| v as usize) else {
        return Ok(None);
    };
    let Some(n) = u16_at(ifd) else {
        return Ok(None);
    };
    let (mut x, mut y, mut unit) = (None, None, 2u16);
    for e in 0..n as usize {
        let at = ifd + 2 + 12 * e;
        let (Some(tag), Some(off)) = (u16_at(at), u32_at(at + 8)) else {
            break;
        };
        let rational = |o: usize| -> Option<f64> {
            let (a, c) = (u32_at(o)?, u32_at(o + 4)?);
            (c != 0).then(|| a as f64 / c as f64)
        };
        match tag {
            282 => x = rational(off as usize),
            283 => y = rational(off as usize),
            296 => unit = u16_at(at + 8).unwrap_or(2),
            _ => {}
        }
    }
    let unit_m = match unit {
        2 => 0.0254,
        3 => 0.01,
        _ => return Ok(None),
    };
    match (x, y) {
        (Some(x), Some(y)) => square(path, x, y, unit_m, "TIFF XResolution"),
        _ => Ok(None),
    }
}

/// The resolution an image file declares (see the module documentation), or `None`.
pub fn resolution(path: &Path) -> Result<Option<Resolution>> {
    use std::io::Read;
    let mut head = Vec::new();
    std::fs::File::open(path)
        .map_err(|e| Error::io(path, e))?
        .take(1 << 20)
        .read_to_end(&mut head)
        .map_err(|e| Error::io(path, e))?;
    if head.starts_with(b"\x89PNG\r\n\x1a\n") {
        png_resolution(path, &head)
    } else if head.starts_with(&[0xFF, 0xD8]) {
        jpeg_resolution(path, &head)
    } else if head.starts_with(b"II*\0") || head.starts_with(b"MM\0*") {
        tiff_resolution(path, &head)
    } else {
        Ok(None)
    }
}

/// The channel an optical density is read in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Channel {
    /// Rec. 709 luma `0.2126 R + 0.7152 G + 0.0722 B`.
    #[default]
    Luma,
    /// The red channel.
    Red,
    /// The green channel.
    Green,
    /// The blue channel.
    Blue,
}

impl Channel {
    /// The complementary channel of a stain colour: the one in which it is darkest.
    pub fn complement_of(stain_rgb: [f64; 3]) -> Channel {
        let k = (0..3)
            .min_by(|&a, &b| stain_rgb[a].total_cmp(&stain_rgb[b]))
            .unwrap_or(1);
        [Channel::Red, Channel::Green, Channel::Blue][k]
    }

    /// The channel value (0–255) of a colour.
    pub fn value(self, rgb: [f64; 3]) -> f64 {
        match self {
            Channel::Luma => 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2],
            Channel::Red => rgb[0],
            Channel::Green => rgb[1],
            Channel::Blue => rgb[2],
        }
    }

    /// Optical density `log10(255 / v)` of a colour in this channel (v floored at 0.5).
    pub fn density(self, rgb: [f64; 3]) -> f64 {
        (255.0 / self.value(rgb).max(0.5)).log10()
    }

    /// Name in outputs.
    pub fn name(self) -> &'static str {
        match self {
            Channel::Luma => "luma",
            Channel::Red => "red",
            Channel::Green => "green",
            Channel::Blue => "blue",
        }
    }
}

/// Gaussian smoothing of one field (σ in pixels; separable, truncated at 3σ, mirrored border).
fn smooth_field(f: &Array2<f64>, sigma: f64) -> Array2<f64> {
    let r = (3.0 * sigma).ceil() as isize;
    let w: Vec<f64> = (-r..=r)
        .map(|k| (-(k * k) as f64 / (2.0 * sigma * sigma)).exp())
        .collect();
    let sum: f64 = w.iter().sum();
    let w: Vec<f64> = w.iter().map(|v| v / sum).collect();
    let mirror = |k: isize, n: usize| -> usize {
        let n = n as isize;
        let mut k = k;
        // Reflect about the border pixels until inside (whole-sample symmetric).
        while k < 0 || k >= n {
            k = if k < 0 { -k - 1 } else { 2 * n - k - 1 };
        }
        k as usize
    };
    let (nx, ny) = f.dim();
    let mut tmp = Array2::<f64>::zeros((nx, ny));
    for i in 0..nx {
        for j in 0..ny {
            tmp[[i, j]] = (-r..=r)
                .zip(&w)
                .map(|(k, wk)| wk * f[[mirror(i as isize + k, nx), j]])
                .sum::<f64>();
        }
    }
    let mut out = Array2::<f64>::zeros((nx, ny));
    for i in 0..nx {
        for j in 0..ny {
            out[[i, j]] = (-r..=r)
                .zip(&w)
                .map(|(k, wk)| wk * tmp[[i, mirror(j as isize + k, ny)]])
                .sum();
        }
    }
    out
}

/// Smooth every channel of `img` with a Gaussian of standard deviation `sigma_px` pixels.
pub fn smooth(img: &mut RgbImage, sigma_px: f64) -> Result<()> {
    if !(sigma_px.is_finite() && sigma_px > 0.0) {
        return Err(Error::param(
            "smoothing",
            format!("σ must be finite and > 0 pixels, got {}", num(sigma_px)),
        ));
    }
    let (nx, ny) = img.dim();
    if sigma_px > 0.25 * nx.min(ny) as f64 {
        return Err(Error::param(
            "smoothing",
            format!(
                "σ = {} pixels is more than a quarter of the {nx} × {ny} image",
                num(sigma_px)
            ),
        ));
    }
    img.r = smooth_field(&img.r, sigma_px);
    img.g = smooth_field(&img.g, sigma_px);
    img.b = smooth_field(&img.b, sigma_px);
    Ok(())
}

/// Density of the unstained paper and its noise (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct PaperLevel {
    /// Mode of the density histogram.
    pub density: f64,
    /// Robust standard deviation of the paper's density.
    pub noise: f64,
    /// Densities above this are stained: `density + max(5·noise, 0.01)`.
    pub stained_above: f64,
}

/// Estimate the paper level from the densities of every pixel.
pub fn paper_level(densities: impl Iterator<Item = f64> + Clone) -> PaperLevel {
    const BIN: f64 = 0.002;
    let nb = (3.0 / BIN) as usize + 1;
    let mut hist = vec![0usize; nb];
    for d in densities.clone() {
        let k = ((d.max(0.0) / BIN) as usize).min(nb - 1);
        hist[k] += 1;
    }
    let mode_bin = (0..nb)
        .max_by_key(|&k| (hist[k], usize::MAX - k))
        .unwrap_or(0);
    let mode = (mode_bin as f64 + 0.5) * BIN;
    // Half width at half maximum on the low side, interpolated between bins.
    let half = hist[mode_bin] as f64 / 2.0;
    let mut hwhm = 0.0;
    for k in (0..mode_bin).rev() {
        if (hist[k] as f64) < half {
            let (a, b) = (hist[k] as f64, hist[k + 1] as f64);
            let t = if b > a { (b - half) / (b - a) } else { 0.0 };
            hwhm = ((mode_bin - k - 1) as f64 + t) * BIN;
            break;
        }
    }
    let _ = densities;
    let noise = hwhm / (2.0 * std::f64::consts::LN_2).sqrt();
    PaperLevel {
        density: mode,
        noise,
        stained_above: mode + (5.0 * noise).max(0.01),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn complement_channel_and_densities() {
        assert_eq!(Channel::complement_of([230.0, 60.0, 110.0]), Channel::Green);
        assert_eq!(Channel::complement_of([20.0, 40.0, 200.0]), Channel::Red);
        assert!((Channel::Green.density([255.0, 25.5, 0.0]) - 1.0).abs() < 1e-12);
        assert_eq!(Channel::Red.density([255.0, 0.0, 0.0]), 0.0);
    }

    #[test]
    fn smoothing_keeps_constants_and_the_mean() {
        let f = Array2::from_shape_fn((20, 15), |(i, j)| ((i * 3 + j) % 7) as f64);
        let s = smooth_field(&f, 1.5);
        assert!(
            (s.sum() - f.sum()).abs() < 1e-6 * f.sum(),
            "{} {}",
            s.sum(),
            f.sum()
        );
        let c = smooth_field(&Array2::from_elem((9, 9), 4.0), 2.0);
        assert!(c.iter().all(|v| (v - 4.0).abs() < 1e-12));
    }

    #[test]
    fn paper_level_ignores_the_stain() {
        // Paper at D ≈ 0.02 ± 0.003 (deterministic spread), 10 % stained at 0.3.
        let d: Vec<f64> = (0..10000)
            .map(|k| {
                if k % 10 == 0 {
                    0.3
                } else {
                    0.02 + 0.003 * ((k * 7919 % 1000) as f64 / 500.0 - 1.0)
                }
            })
            .collect();
        let p = paper_level(d.iter().copied());
        assert!((p.density - 0.02).abs() < 0.003, "{p:?}");
        assert!(p.stained_above > 0.025 && p.stained_above < 0.05, "{p:?}");
    }

    /// A 2 × 2 white PNG declaring `ppm` pixels per metre (pHYs).
    fn write_png_with_density(path: &Path, ppm: u32) {
        let f = std::fs::File::create(path).unwrap();
        let mut e = ::png::Encoder::new(std::io::BufWriter::new(f), 2, 2);
        e.set_color(::png::ColorType::Rgb);
        e.set_pixel_dims(Some(::png::PixelDimensions {
            xppu: ppm,
            yppu: ppm,
            unit: ::png::Unit::Meter,
        }));
        e.write_header()
            .unwrap()
            .write_image_data(&[255; 12])
            .unwrap();
    }

    /// A JPEG start with a JFIF header declaring `density` in `units` (1: per inch, 2: per cm).
    fn write_jfif_with_density(path: &Path, units: u8, density: u16) {
        let [hi, lo] = density.to_be_bytes();
        let mut jpg = vec![0xFF, 0xD8, 0xFF, 0xE0, 0x00, 0x10];
        jpg.extend_from_slice(b"JFIF\0\x01\x01");
        jpg.extend_from_slice(&[units, hi, lo, hi, lo, 0, 0, 0xFF, 0xDA]);
        std::fs::write(path, &jpg).unwrap();
    }

    #[test]
    fn resolutions_from_headers() {
        let dir = tempfile::tempdir().unwrap();
        // A JFIF header declaring 200 dpi.
        let p = dir.path().join("a.jpg");
        write_jfif_with_density(&p, 1, 200);
        let r = resolution(&p).unwrap().unwrap();
        assert!((r.dpi - 200.0).abs() < 1e-12);
        assert!((r.pixel_size_mm() - 0.127).abs() < 1e-12);
        // A PNG written with pHYs: 11811 px/m = 300 dpi (to 0.01 %).
        let png = dir.path().join("a.png");
        write_png_with_density(&png, 11811);
        let r = resolution(&png).unwrap().unwrap();
        assert!((r.dpi - 300.0).abs() < 0.05, "{r:?}");
    }

    #[test]
    fn software_default_resolutions_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        // 2835 px/m = 72.009 dpi and 3780 px/m = 96.012 dpi: the PNG defaults; 2953 px/m =
        // 75.0 dpi, the lowest scanner setting, is taken as declared.
        for (ppm, refused) in [(2835, true), (3780, true), (2953, false)] {
            let png = dir.path().join(format!("{ppm}.png"));
            write_png_with_density(&png, ppm);
            match resolution(&png) {
                Err(e) => {
                    assert!(refused, "{ppm} px/m refused: {e}");
                    let msg = e.to_string();
                    assert!(
                        msg.contains("--pixel-size-mm") && msg.contains(&format!("{ppm}.png")),
                        "{msg}"
                    );
                }
                Ok(r) => assert!(!refused, "{ppm} px/m accepted: {r:?}"),
            }
        }
        // A JFIF header declaring 72 dpi (unit 1: dots per inch).
        let p = dir.path().join("a.jpg");
        write_jfif_with_density(&p, 1, 72);
        let msg = resolution(&p).unwrap_err().to_string();
        assert!(
            msg.contains("72 dpi (JPEG JFIF)") && msg.contains("--pixel-size-mm"),
            "{msg}"
        );
        // The same default in dots per centimetre (unit 2: 38 /cm = 96.52 dpi).
        write_jfif_with_density(&p, 2, 38);
        let msg = resolution(&p).unwrap_err().to_string();
        assert!(msg.contains("96.52 dpi"), "{msg}");
    }
}
