//! An image of floats rather than a film's exact sums: what an output transform (the denoiser)
//! makes of a film, with named layers beside it (the noisy image, feature buffers), as Cycles'
//! and Mitsuba 3's multi-layer EXR outputs hold their passes. Written in any output format: an
//! EXR holds every layer (`noisy.R`, `albedo.R`, `normal.X`, ...), the others the main image.

use super::output::{ImageFormat, Transfer};
use anyhow::Context;
use exr::prelude::*;
use std::io::{BufWriter, Write};

/// A layer beside the main image: its name and channel names, and its pixels.
#[derive(Clone, Debug)]
pub struct NamedLayer {
    /// As in `noisy.R`: the channels' prefix.
    pub name: &'static str,
    pub channels: [&'static str; 3],
    pub pixels: Vec<[f32; 3]>,
}

/// Row-major RGB from the top, `width` x `height`, and the layers beside it.
#[derive(Clone, Debug)]
pub struct FloatImage {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<[f32; 3]>,
    pub layers: Vec<NamedLayer>,
}

impl FloatImage {
    /// The image encoded in `format`; 8-bit formats use `transfer`.
    pub fn encode(&self, format: ImageFormat, transfer: Transfer) -> anyhow::Result<Vec<u8>> {
        let (w, h) = (self.width, self.height);
        let mut out = std::io::Cursor::new(Vec::new());
        let bytes = |p: &[f32; 3]| p.map(|c| transfer.encode(c));
        match format {
            ImageFormat::Png => {
                let levels: Vec<u8> = self.rgb.iter().flat_map(bytes).collect();
                let img = image::RgbImage::from_raw(w, h, levels).context("image buffer size")?;
                img.write_to(&mut out, image::ImageFormat::Png)?;
            }
            ImageFormat::Ppm => {
                let mut text = BufWriter::new(&mut out);
                writeln!(text, "P3\n{w} {h}\n255")?;
                for p in &self.rgb {
                    let [r, g, b] = bytes(p);
                    writeln!(text, "{r} {g} {b}")?;
                }
                text.flush()?;
            }
            ImageFormat::Pfm => {
                let mut data = format!("PF\n{w} {h}\n-1.0\n").into_bytes();
                // PFM stores rows bottom to top; -1.0 marks little-endian.
                for row in self.rgb.chunks(w as usize).rev() {
                    for c in row.iter().flatten() {
                        data.extend_from_slice(&c.to_le_bytes());
                    }
                }
                out.write_all(&data)?;
            }
            ImageFormat::Exr => return self.encode_exr(),
        }
        Ok(out.into_inner())
    }

    fn encode_exr(&self) -> anyhow::Result<Vec<u8>> {
        let channel = |name: String, pixels: &[[f32; 3]], c: usize| {
            AnyChannel::new(
                Text::from(name.as_str()),
                FlatSamples::F32(pixels.iter().map(|p| p[c]).collect()),
            )
        };
        let mut channels = Vec::new();
        for (c, name) in ["R", "G", "B"].iter().enumerate() {
            channels.push(channel(name.to_string(), &self.rgb, c));
        }
        for layer in &self.layers {
            for (c, name) in layer.channels.iter().enumerate() {
                channels.push(channel(format!("{}.{name}", layer.name), &layer.pixels, c));
            }
        }
        let layer = Layer::new(
            (self.width as usize, self.height as usize),
            LayerAttributes::default(),
            Encoding::FAST_LOSSLESS,
            AnyChannels::sort(channels.into()),
        );
        let mut out = std::io::Cursor::new(Vec::new());
        Image::from_layer(layer).write().to_buffered(&mut out)?;
        Ok(out.into_inner())
    }
}
