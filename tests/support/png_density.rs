//! PNG files that declare their resolution (the `pHYs` chunk), shared by the film tests
//! (`tests/film_raw_scan.rs`, `tests/bad_input_catalogue.rs`): the `image` crate writes PNG
//! without one.

/// An 8-bit RGB PNG of `width × height` pixels (`rgb`: row-major, three bytes per pixel)
/// declaring `pixels_per_metre` in both directions (72 dpi = 2835, 254 dpi = 10000).
pub fn rgb_png_with_density(width: u32, height: u32, rgb: &[u8], pixels_per_metre: u32) -> Vec<u8> {
    let mut buf = Vec::new();
    {
        let mut e = png::Encoder::new(&mut buf, width, height);
        e.set_color(png::ColorType::Rgb);
        e.set_pixel_dims(Some(png::PixelDimensions {
            xppu: pixels_per_metre,
            yppu: pixels_per_metre,
            unit: png::Unit::Meter,
        }));
        e.write_header().unwrap().write_image_data(rgb).unwrap();
    }
    buf
}
