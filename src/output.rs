//! Writing images. The format follows the file extension; every write goes to a temporary file
//! beside the target and is renamed over it only when complete, so a failed or interrupted render
//! never clobbers an existing image.

use crate::film::Film;
use anyhow::Context;
use std::io::{BufWriter, Write};
use std::path::Path;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// 8-bit, gamma 2.
    Png,
    /// ASCII P3, gamma 2, as the original project wrote.
    Ppm,
    /// Linear float radiance.
    Exr,
    /// Linear float radiance (Portable Float Map).
    Pfm,
}

impl ImageFormat {
    pub fn from_path(path: &Path) -> anyhow::Result<Self> {
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        Ok(match ext.as_str() {
            "png" => ImageFormat::Png,
            "ppm" => ImageFormat::Ppm,
            "exr" => ImageFormat::Exr,
            "pfm" => ImageFormat::Pfm,
            _ => anyhow::bail!(
                "cannot tell the image format of {}: use a .png, .ppm, .exr or .pfm file name",
                path.display()
            ),
        })
    }
}

/// Gamma 2 and 8 bits, as the original: 256 * clamp(sqrt(c), 0, 0.999).
pub fn to_srgb8(linear: f32) -> u8 {
    let c = if linear.is_finite() {
        linear.max(0.0)
    } else {
        0.0
    };
    (256.0 * c.sqrt().clamp(0.0, 0.999)) as u8
}

/// Writes `film`'s mean image to `path` atomically, in the format its extension names.
pub fn write_image(path: &Path, film: &Film) -> anyhow::Result<()> {
    let format = ImageFormat::from_path(path)?;
    let rgb = film.mean_rgb();
    let (w, h) = (film.width, film.height);
    write_atomically(path, |out| match format {
        ImageFormat::Png => {
            let bytes: Vec<u8> = rgb.iter().flatten().map(|&c| to_srgb8(c)).collect();
            let img = image::RgbImage::from_raw(w, h, bytes).context("image buffer size")?;
            img.write_to(out, image::ImageFormat::Png)?;
            Ok(())
        }
        ImageFormat::Ppm => {
            let mut text = BufWriter::new(out);
            writeln!(text, "P3\n{w} {h}\n255")?;
            for row in rgb.chunks(w as usize) {
                for px in row {
                    writeln!(
                        text,
                        "{} {} {}",
                        to_srgb8(px[0]),
                        to_srgb8(px[1]),
                        to_srgb8(px[2])
                    )?;
                }
            }
            text.flush()?;
            Ok(())
        }
        ImageFormat::Exr => {
            let floats: Vec<f32> = rgb.iter().flatten().copied().collect();
            let img = image::Rgb32FImage::from_raw(w, h, floats).context("image buffer size")?;
            img.write_to(out, image::ImageFormat::OpenExr)?;
            Ok(())
        }
        ImageFormat::Pfm => {
            let mut bytes = format!("PF\n{w} {h}\n-1.0\n").into_bytes();
            // PFM stores rows bottom to top; -1.0 marks little-endian.
            for row in rgb.chunks(w as usize).rev() {
                for c in row.iter().flatten() {
                    bytes.extend_from_slice(&c.to_le_bytes());
                }
            }
            out.write_all(&bytes)?;
            Ok(())
        }
    })
}

/// Reads a PFM written by [`write_image`] (or any little- or big-endian RGB PFM) as
/// (width, height, row-major RGB from the top).
pub fn read_pfm(path: &Path) -> anyhow::Result<(u32, u32, Vec<[f32; 3]>)> {
    let bytes = std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
    let mut fields = Vec::new();
    let mut pos = 0;
    while fields.len() < 4 && pos < bytes.len() {
        while pos < bytes.len() && bytes[pos].is_ascii_whitespace() {
            pos += 1;
        }
        let start = pos;
        while pos < bytes.len() && !bytes[pos].is_ascii_whitespace() {
            pos += 1;
        }
        fields.push(String::from_utf8_lossy(&bytes[start..pos]).into_owned());
    }
    pos += 1;
    let bad = || anyhow::anyhow!("{} is not an RGB PFM file", path.display());
    if fields.len() < 4 || fields[0] != "PF" {
        return Err(bad());
    }
    let w: u32 = fields[1].parse().map_err(|_| bad())?;
    let h: u32 = fields[2].parse().map_err(|_| bad())?;
    let little = fields[3].parse::<f32>().map_err(|_| bad())? < 0.0;
    let data = bytes.get(pos..).ok_or_else(bad)?;
    if data.len() < w as usize * h as usize * 12 {
        return Err(bad());
    }
    let value = |i: usize| {
        let b: [u8; 4] = data[4 * i..4 * i + 4].try_into().unwrap_or_default();
        if little {
            f32::from_le_bytes(b)
        } else {
            f32::from_be_bytes(b)
        }
    };
    let mut rgb = vec![[0.0; 3]; (w * h) as usize];
    for y in 0..h as usize {
        let src_row = h as usize - 1 - y;
        for x in 0..w as usize {
            let i = (src_row * w as usize + x) * 3;
            rgb[y * w as usize + x] = [value(i), value(i + 1), value(i + 2)];
        }
    }
    Ok((w, h, rgb))
}

/// Runs `write` into a temporary file beside `path`, then renames it over `path`.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut std::io::Cursor<Vec<u8>>) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let mut buffer = std::io::Cursor::new(Vec::new());
    write(&mut buffer).with_context(|| format!("cannot encode {}", path.display()))?;
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let mut builder = tempfile::Builder::new();
    builder.prefix(".rt-gpu-").suffix(".tmp");
    // Temporary files are private (0600); an image is an ordinary file.
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o644));
    let mut tmp = builder
        .tempfile_in(dir)
        .with_context(|| format!("cannot create a file in {}", dir.display()))?;
    tmp.write_all(buffer.get_ref())
        .and_then(|_| tmp.as_file().sync_all())
        .with_context(|| format!("cannot write {}", path.display()))?;
    tmp.persist(path)
        .map_err(|e| e.error)
        .with_context(|| format!("cannot write {}", path.display()))?;
    Ok(())
}
