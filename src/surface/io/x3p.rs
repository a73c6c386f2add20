//! ISO 25178-72 (ISO 5436-2) XML 3D surface profiles, `.x3p`.
//!
//! An x3p file is a zip archive holding `main.xml` (the description) and the binary point data
//! (`bindata/data.bin`, named by `Record3/DataLink/PointDataLink`). What is read:
//!
//! - `Record1/Axes/CX`, `CY`: `AxisType` must be `I` (incremental: a regular grid) with the
//!   spacing `Increment` in metres; `CZ`: `AxisType` `A` (absolute), `DataType` `D` (f64), `F`
//!   (f32), `L` (signed 32-bit integer) or `I` (signed 16-bit integer; as the openGPS reference
//!   library's `OGPS_Int32`/`OGPS_Int16` and Gwyddion's x3p reader), optional `Increment`
//!   (scale) and `Offset`.
//! - `Record3/MatrixDimension/SizeX`, `SizeY` (points along x, y), `SizeZ` must be 1.
//! - The binary data are little-endian, x fastest: value `k = j·SizeX + i` is the height at
//!   `(i·dx, j·dy)`; its length must be exactly `SizeX·SizeY·size(DataType)`. When
//!   `MD5ChecksumPointData` is given it must match the data.
//!
//! - Missing points: a NaN height (float types), or a clear bit in the validity mask
//!   `Record3/DataLink/ValidPointsLink` (`bindata/valid.bin`: one bit per point in the order of
//!   the heights, least-significant bit first, 1 = valid, `⌈SizeX·SizeY/8⌉` bytes; checked
//!   against `MD5ChecksumValidPoints` when given). Such a map is read as a
//!   [`MaskedGrid`]; the writer writes NaN heights and the
//!   validity mask for it.
//! - Limits: `SizeX·SizeY` is checked against [`crate::core::limits::MAX_GRID_POINTS`] and the memory
//!   available, and every entry is read with at most the bytes `main.xml` promises, before
//!   anything is allocated for it.
//!
//! Heights are in metres. The format has no notion of periodicity; the writer records a
//! periodic patch as the comment `asperity:periodic` in `Record2/Comment`, which the reader
//! honours.

use crate::core::error::{Error, Result};
use crate::core::grid::Grid2;
use crate::core::output::write_atomic_via_path;
use crate::surface::missing::MaskedGrid;
use crate::surface::topography::Topography;
use md5::{Digest, Md5};
use ndarray::Array2;
use quick_xml::events::Event;
use std::collections::HashMap;
use std::io::{Read, Write};
use std::path::Path;

/// Marker written into `Record2/Comment` for periodic patches.
pub const PERIODIC_MARK: &str = "asperity:periodic";

/// Element texts of `main.xml` keyed by their path without the root, e.g.
/// `Record1/Axes/CX/Increment`.
fn xml_texts(path: &Path, xml: &str) -> Result<HashMap<String, String>> {
    let mut reader = quick_xml::Reader::from_str(xml);
    reader.config_mut().trim_text(true);
    let mut stack: Vec<String> = Vec::new();
    let mut out = HashMap::new();
    loop {
        let ev = reader.read_event().map_err(|e| {
            Error::parse(
                path,
                0,
                format!(
                    "main.xml is not well-formed XML (byte {}): {e}",
                    reader.buffer_position()
                ),
            )
        })?;
        match ev {
            Event::Start(e) => {
                stack.push(String::from_utf8_lossy(e.local_name().as_ref()).into_owned())
            }
            Event::End(_) => {
                stack.pop();
            }
            Event::Text(t) if stack.len() > 1 => {
                let text = t
                    .unescape()
                    .map_err(|e| Error::parse(path, 0, format!("main.xml: {e}")))?;
                out.insert(stack[1..].join("/"), text.trim().to_string());
            }
            Event::Eof => break,
            _ => {}
        }
    }
    Ok(out)
}

struct Description {
    nx: usize,
    ny: usize,
    dx: f64,
    dy: f64,
    data_type: char,
    z_scale: f64,
    z_offset: f64,
    link: String,
    md5: Option<String>,
    valid_link: Option<String>,
    valid_md5: Option<String>,
    periodic: bool,
}

fn describe(path: &Path, t: &HashMap<String, String>) -> Result<Description> {
    let get = |k: &str| {
        t.get(k)
            .map(String::as_str)
            .ok_or_else(|| Error::parse(path, 0, format!("main.xml lacks `{k}`")))
    };
    let num = |k: &str| -> Result<f64> {
        let s = get(k)?;
        s.parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| {
                Error::parse(path, 0, format!("main.xml: `{k}` = `{s}` is not a number"))
            })
    };
    let size = |k: &str| -> Result<usize> {
        let s = get(k)?;
        s.parse::<usize>().ok().filter(|&v| v > 0).ok_or_else(|| {
            Error::parse(
                path,
                0,
                format!("main.xml: `{k}` = `{s}` is not a positive integer"),
            )
        })
    };
    if let Some(ft) = t.get("Record1/FeatureType") {
        if ft != "SUR" {
            return Err(Error::parse(
                path,
                0,
                format!("x3p FeatureType `{ft}`: only areal surfaces (`SUR`) are supported"),
            ));
        }
    }
    for ax in ["CX", "CY"] {
        let at = get(&format!("Record1/Axes/{ax}/AxisType"))?;
        if at != "I" {
            return Err(Error::parse(
                path,
                0,
                format!(
                    "x3p axis {ax} has AxisType `{at}`; only incremental (`I`) grids are supported"
                ),
            ));
        }
    }
    let az = get("Record1/Axes/CZ/AxisType")?;
    if az != "A" {
        return Err(Error::parse(
            path,
            0,
            format!("x3p axis CZ has AxisType `{az}`, expected `A`"),
        ));
    }
    let dt = get("Record1/Axes/CZ/DataType")?;
    let data_type = match dt {
        "D" | "F" | "L" | "I" => dt.chars().next().unwrap_or('D'),
        _ => {
            return Err(Error::parse(
                path,
                0,
                format!("x3p CZ DataType `{dt}` unknown (D, F, L, I)"),
            ))
        }
    };
    let nz = size("Record3/MatrixDimension/SizeZ")?;
    if nz != 1 {
        return Err(Error::parse(
            path,
            0,
            format!("x3p SizeZ = {nz}: layered data are not supported"),
        ));
    }
    let opt = |k: &str, default: f64| -> Result<f64> {
        if t.contains_key(k) {
            num(k)
        } else {
            Ok(default)
        }
    };
    Ok(Description {
        nx: size("Record3/MatrixDimension/SizeX")?,
        ny: size("Record3/MatrixDimension/SizeY")?,
        dx: num("Record1/Axes/CX/Increment")?,
        dy: num("Record1/Axes/CY/Increment")?,
        data_type,
        z_scale: opt("Record1/Axes/CZ/Increment", 1.0)?,
        z_offset: opt("Record1/Axes/CZ/Offset", 0.0)?,
        link: get("Record3/DataLink/PointDataLink")?.to_string(),
        md5: t.get("Record3/DataLink/MD5ChecksumPointData").cloned(),
        valid_link: t
            .get("Record3/DataLink/ValidPointsLink")
            .filter(|l| !l.is_empty())
            .cloned(),
        valid_md5: t.get("Record3/DataLink/MD5ChecksumValidPoints").cloned(),
        periodic: t
            .get("Record2/Comment")
            .is_some_and(|c| c.contains(PERIODIC_MARK)),
    })
}

fn bytes_per_value(data_type: char) -> usize {
    match data_type {
        'D' => 8,
        'F' | 'L' => 4,
        _ => 2,
    }
}

/// Decode little-endian values of the given x3p data type.
fn decode(data_type: char, b: &[u8]) -> f64 {
    match data_type {
        'D' => f64::from_le_bytes(b.try_into().expect("8 bytes")),
        'F' => f32::from_le_bytes(b.try_into().expect("4 bytes")) as f64,
        'L' => i32::from_le_bytes(b.try_into().expect("4 bytes")) as f64,
        _ => i16::from_le_bytes(b.try_into().expect("2 bytes")) as f64,
    }
}

/// Read at most `limit` bytes of the archive entry `name` (its declared size must equal
/// `expected` when given).
fn read_entry(
    path: &Path,
    zip: &mut zip::ZipArchive<std::fs::File>,
    name: &str,
    what: &str,
    expected: Option<u64>,
    limit: u64,
) -> Result<Vec<u8>> {
    let entry = zip.by_name(name).map_err(|e| {
        Error::parse(
            path,
            0,
            format!("x3p {what} `{name}` missing from the archive: {e}"),
        )
    })?;
    if let Some(want) = expected {
        if entry.size() != want {
            return Err(Error::parse(
                path,
                0,
                format!(
                    "x3p {what} `{name}` has {} bytes, but main.xml promises {want}: truncated or \
                     inconsistent",
                    entry.size()
                ),
            ));
        }
    }
    let mut buf = Vec::with_capacity(entry.size().min(limit) as usize);
    entry
        .take(limit + 1)
        .read_to_end(&mut buf)
        .map_err(|e| Error::parse(path, 0, format!("reading x3p {what} `{name}`: {e}")))?;
    if buf.len() as u64 > limit {
        return Err(Error::limit(
            path.display().to_string(),
            format!("x3p {what} `{name}` holds more than {limit} bytes"),
        ));
    }
    if let Some(want) = expected {
        if buf.len() as u64 != want {
            return Err(Error::parse(
                path,
                0,
                format!(
                    "x3p {what} `{name}` truncated: {} of {want} bytes",
                    buf.len()
                ),
            ));
        }
    }
    Ok(buf)
}

/// Check an MD5 checksum given in main.xml.
fn check_md5(path: &Path, bytes: &[u8], want: Option<&String>, what: &str) -> Result<()> {
    if let Some(want) = want {
        let got = format!("{:x}", Md5::digest(bytes));
        if !got.eq_ignore_ascii_case(want.trim()) {
            return Err(Error::parse(
                path,
                0,
                format!("x3p {what} MD5 {got} does not match main.xml's {want}: corrupted"),
            ));
        }
    }
    Ok(())
}

/// Read an x3p file: a complete height map, or one with missing points.
pub fn read_topography(path: &Path) -> Result<Topography> {
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let mut zip = zip::ZipArchive::new(file)
        .map_err(|e| Error::parse(path, 0, format!("not a valid x3p (zip) archive: {e}")))?;
    let xml = read_entry(
        path,
        &mut zip,
        "main.xml",
        "description",
        None,
        crate::core::limits::MAX_XML_BYTES,
    )?;
    let xml = String::from_utf8(xml)
        .map_err(|e| Error::parse(path, 0, format!("main.xml is not UTF-8: {e}")))?;
    let d = describe(path, &xml_texts(path, &xml)?)?;
    crate::core::limits::check_grid(
        &path.display().to_string(),
        d.nx,
        d.ny,
        crate::core::limits::STATS_BYTES_PER_POINT,
    )?;
    let n = d.nx * d.ny;
    let w = bytes_per_value(d.data_type);
    let expected = (n * w) as u64;
    let bin = read_entry(
        path,
        &mut zip,
        &d.link,
        "point data",
        Some(expected),
        expected,
    )?;
    check_md5(path, &bin, d.md5.as_ref(), "point data")?;
    let valid: Option<Vec<u8>> = match &d.valid_link {
        None => None,
        Some(link) => {
            let bytes = n.div_ceil(8) as u64;
            let v = read_entry(path, &mut zip, link, "validity mask", Some(bytes), bytes)?;
            check_md5(path, &v, d.valid_md5.as_ref(), "validity mask")?;
            Some(v)
        }
    };
    let mut heights = Array2::<f64>::zeros((d.nx, d.ny));
    for (k, chunk) in bin.chunks_exact(w).enumerate() {
        let (i, j) = (k % d.nx, k / d.nx);
        let is_valid = valid.as_ref().is_none_or(|v| v[k / 8] >> (k % 8) & 1 == 1);
        heights[[i, j]] = if is_valid {
            d.z_offset + d.z_scale * decode(d.data_type, chunk)
        } else {
            f64::NAN
        };
    }
    if let Some(((i, j), v)) = heights.indexed_iter().find(|(_, v)| v.is_infinite()) {
        return Err(Error::parse(
            path,
            0,
            format!("x3p height at point ({i}, {j}) is {v}"),
        ));
    }
    Topography::from_heights(heights, d.dx, d.dy, d.periodic)
        .map_err(|e| Error::parse(path, 0, e.to_string()))
}

/// Read a complete x3p height map (an error when points are missing).
pub fn read(path: &Path) -> Result<Grid2> {
    read_topography(path)?.into_area(&path.display().to_string())
}

/// ISO 8601 UTC timestamp of now (for `Record2/Date`), without a date-time crate:
/// days-to-civil conversion of Howard Hinnant's `chrono`-compatible algorithm.
fn utc_now_iso8601() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs() as i64)
        .unwrap_or(0);
    let (days, rem) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}Z",
        rem / 3600,
        (rem % 3600) / 60,
        rem % 60
    )
}

/// The `main.xml` of a grid written with f64 (`D`) heights (and a validity mask when
/// `md5_valid` is given).
fn main_xml(
    (nx, ny, dx, dy, periodic): (usize, usize, f64, f64, bool),
    md5_data: &str,
    md5_valid: Option<&str>,
) -> String {
    let comment = if periodic { PERIODIC_MARK } else { "" };
    let valid = md5_valid
        .map(|m| {
            format!(
                "<ValidPointsLink>bindata/valid.bin</ValidPointsLink><MD5ChecksumValidPoints>{m}</MD5ChecksumValidPoints>"
            )
        })
        .unwrap_or_default();
    let date = utc_now_iso8601();
    format!(
        r#"<?xml version="1.0" encoding="UTF-8" standalone="no" ?>
<p:ISO5436_2 xmlns:p="http://www.opengps.eu/2008/ISO5436_2" xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" xsi:schemaLocation="http://www.opengps.eu/2008/ISO5436_2 http://www.opengps.eu/2008/ISO5436_2/ISO5436_2.xsd">
  <Record1>
    <Revision>ISO5436 - 2000</Revision>
    <FeatureType>SUR</FeatureType>
    <Axes>
      <CX><AxisType>I</AxisType><DataType>D</DataType><Increment>{dx:?}</Increment><Offset>0</Offset></CX>
      <CY><AxisType>I</AxisType><DataType>D</DataType><Increment>{dy:?}</Increment><Offset>0</Offset></CY>
      <CZ><AxisType>A</AxisType><DataType>D</DataType></CZ>
    </Axes>
  </Record1>
  <Record2>
    <Date>{date}</Date>
    <Instrument>
      <Manufacturer>asperity</Manufacturer>
      <Model>asperity</Model>
      <Serial>not available</Serial>
      <Version>{version}</Version>
    </Instrument>
    <CalibrationDate>{date}</CalibrationDate>
    <ProbingSystem><Type>Software</Type><Identification>asperity</Identification></ProbingSystem>
    <Comment>{comment}</Comment>
  </Record2>
  <Record3>
    <MatrixDimension><SizeX>{nx}</SizeX><SizeY>{ny}</SizeY><SizeZ>1</SizeZ></MatrixDimension>
    <DataLink><PointDataLink>bindata/data.bin</PointDataLink><MD5ChecksumPointData>{md5_data}</MD5ChecksumPointData>{valid}</DataLink>
  </Record3>
  <Record4><ChecksumFile>md5checksum.hex</ChecksumFile></Record4>
</p:ISO5436_2>
"#,
        version = env!("CARGO_PKG_VERSION"),
    )
}

/// Write `grid` as an x3p archive (f64 heights in m), atomically.
pub fn write(path: &Path, grid: &Grid2) -> Result<()> {
    write_heights(path, &grid.heights, grid.dx, grid.dy, grid.periodic)
}

/// Write a map with missing points: NaN heights and the validity mask `bindata/valid.bin`.
pub fn write_masked(path: &Path, grid: &MaskedGrid) -> Result<()> {
    write_heights(path, &grid.heights, grid.dx, grid.dy, grid.periodic)
}

fn write_heights(path: &Path, h: &Array2<f64>, dx: f64, dy: f64, periodic: bool) -> Result<()> {
    let (nx, ny) = h.dim();
    let mut bin = Vec::with_capacity(nx * ny * 8);
    let mut valid = vec![0u8; (nx * ny).div_ceil(8)];
    let mut any_missing = false;
    for j in 0..ny {
        for i in 0..nx {
            let v = h[[i, j]];
            bin.extend_from_slice(&v.to_le_bytes());
            let k = j * nx + i;
            if v.is_nan() {
                any_missing = true;
            } else {
                valid[k / 8] |= 1 << (k % 8);
            }
        }
    }
    let md5_data = format!("{:X}", Md5::digest(&bin));
    let md5_valid = any_missing.then(|| format!("{:X}", Md5::digest(&valid)));
    let xml = main_xml((nx, ny, dx, dy, periodic), &md5_data, md5_valid.as_deref());
    let md5_xml = format!("{:x} *main.xml\n", Md5::digest(xml.as_bytes()));
    write_atomic_via_path(path, |tmp| {
        let zerr = |e: zip::result::ZipError| Error::parse(path, 0, format!("writing x3p: {e}"));
        let ioerr = |e| Error::io(path, e);
        let file = std::fs::File::create(tmp).map_err(|e| Error::io(tmp, e))?;
        let mut z = zip::ZipWriter::new(file);
        let opts = zip::write::SimpleFileOptions::default()
            .compression_method(zip::CompressionMethod::Deflated);
        z.start_file("main.xml", opts).map_err(zerr)?;
        z.write_all(xml.as_bytes()).map_err(ioerr)?;
        z.start_file("bindata/data.bin", opts).map_err(zerr)?;
        z.write_all(&bin).map_err(ioerr)?;
        if any_missing {
            z.start_file("bindata/valid.bin", opts).map_err(zerr)?;
            z.write_all(&valid).map_err(ioerr)?;
        }
        z.start_file("md5checksum.hex", opts).map_err(zerr)?;
        z.write_all(md5_xml.as_bytes()).map_err(ioerr)?;
        z.finish().map_err(zerr)?;
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An x3p archive with the given CZ data type, scale/offset and raw little-endian data.
    fn archive(path: &Path, data_type: &str, z: &str, nx: usize, ny: usize, bin: &[u8]) {
        let xml = format!(
            "<?xml version=\"1.0\"?><p:ISO5436_2 xmlns:p=\"http://www.opengps.eu/2008/ISO5436_2\">\
             <Record1><Revision>ISO5436 - 2000</Revision><FeatureType>SUR</FeatureType><Axes>\
             <CX><AxisType>I</AxisType><DataType>D</DataType><Increment>2e-6</Increment></CX>\
             <CY><AxisType>I</AxisType><DataType>D</DataType><Increment>3e-6</Increment></CY>\
             <CZ><AxisType>A</AxisType><DataType>{data_type}</DataType>{z}</CZ></Axes></Record1>\
             <Record3><MatrixDimension><SizeX>{nx}</SizeX><SizeY>{ny}</SizeY><SizeZ>1</SizeZ>\
             </MatrixDimension><DataLink><PointDataLink>bindata/data.bin</PointDataLink></DataLink>\
             </Record3></p:ISO5436_2>"
        );
        let mut z = zip::ZipWriter::new(std::fs::File::create(path).unwrap());
        let o = zip::write::SimpleFileOptions::default();
        z.start_file("main.xml", o).unwrap();
        z.write_all(xml.as_bytes()).unwrap();
        z.start_file("bindata/data.bin", o).unwrap();
        z.write_all(bin).unwrap();
        z.finish().unwrap();
    }

    #[test]
    fn data_types_scale_offset_and_axis_order() {
        let dir = tempfile::tempdir().unwrap();
        let (nx, ny) = (3, 2);
        // Value k = j·nx + i, so height(i, j) identifies the axis order.
        let f32_bin: Vec<u8> = (0..nx * ny)
            .flat_map(|k| (k as f32 * 0.5).to_le_bytes())
            .collect();
        let p = dir.path().join("f.x3p");
        archive(&p, "F", "", nx, ny, &f32_bin);
        let g = read(&p).unwrap();
        assert_eq!((g.nx(), g.ny()), (3, 2));
        assert_eq!((g.dx, g.dy), (2e-6, 3e-6));
        assert!(!g.periodic);
        assert_eq!(g.heights[[2, 1]], 2.5); // k = 1·3 + 2 = 5
        assert_eq!(g.heights[[1, 0]], 0.5);
        let u16_bin: Vec<u8> = (0..nx * ny)
            .flat_map(|k| (k as u16).to_le_bytes())
            .collect();
        let p = dir.path().join("i.x3p");
        archive(
            &p,
            "I",
            "<Increment>1e-9</Increment><Offset>-2e-9</Offset>",
            nx,
            ny,
            &u16_bin,
        );
        let g = read(&p).unwrap();
        assert!((g.heights[[2, 1]] - (5e-9 - 2e-9)).abs() < 1e-24);
        // The integer types are signed: −100 and −5000 increments read below the offset
        // (read as unsigned they were +65 436 and +4 294 962 296 increments).
        let neg16: Vec<u8> = (0..nx * ny)
            .flat_map(|k| if k == 4 { -100i16 } else { k as i16 }.to_le_bytes())
            .collect();
        let p = dir.path().join("i-neg.x3p");
        archive(&p, "I", "<Increment>1e-9</Increment>", nx, ny, &neg16);
        assert!((read(&p).unwrap().heights[[1, 1]] + 100e-9).abs() < 1e-22);
        let neg32: Vec<u8> = (0..nx * ny)
            .flat_map(|k| if k == 4 { -5000i32 } else { k as i32 }.to_le_bytes())
            .collect();
        let p = dir.path().join("l-neg.x3p");
        archive(&p, "L", "<Increment>1e-9</Increment>", nx, ny, &neg32);
        assert!((read(&p).unwrap().heights[[1, 1]] + 5000e-9).abs() < 1e-21);
        let u32_bin: Vec<u8> = (0..nx * ny)
            .flat_map(|k| (k as u32).to_le_bytes())
            .collect();
        let p = dir.path().join("l.x3p");
        archive(&p, "L", "<Increment>1e-6</Increment>", nx, ny, &u32_bin);
        assert!((read(&p).unwrap().heights[[0, 1]] - 3e-6).abs() < 1e-20);
        // Unknown data type and wrong data length are named.
        let p = dir.path().join("q.x3p");
        archive(&p, "Q", "", nx, ny, &u32_bin);
        assert!(read(&p).unwrap_err().to_string().contains("DataType `Q`"));
        let p = dir.path().join("short.x3p");
        archive(&p, "F", "", nx, ny, &f32_bin[..20]);
        assert!(read(&p)
            .unwrap_err()
            .to_string()
            .contains("truncated or inconsistent"));
    }

    #[test]
    fn write_read_round_trip_keeps_periodicity_and_bits() {
        let dir = tempfile::tempdir().unwrap();
        let h = Array2::from_shape_fn((5, 4), |(i, j)| (i as f64 - 2.0) * 1e-7 + j as f64 * 3e-9);
        let g = Grid2::new(h, 1.5e-6, 2.5e-6, true).unwrap();
        let p = dir.path().join("g.x3p");
        write(&p, &g).unwrap();
        assert_eq!(read(&p).unwrap(), g);
        assert!(utc_now_iso8601().ends_with('Z'));
    }
}
