//! An image of floats rather than a film's exact sums: what an output transform (the denoiser)
//! makes of a film, with named layers beside it (the noisy image, feature buffers), as Cycles'
//! and Mitsuba 3's multi-layer EXR outputs hold their passes. Written in any output format: an
//! EXR holds every layer (`noisy.R`, `albedo.R`, `normal.X`, ...), the others the main image.

use super::Film;
use super::output::{ImageFormat, Transfer, encode_image};
use exr::prelude::*;

/// `pixels` (`width` x `height`) as a film of one sample each, a value below zero or not finite
/// (a denoiser's ringing, say) as 0, as films hold them.
pub fn film_of(width: u32, height: u32, pixels: &[[f32; 3]]) -> Film {
    let mut film = Film::new(width, height);
    for (stats, value) in film.pixels.iter_mut().zip(pixels) {
        let kept = value.map(|c| if c.is_finite() && c > 0.0 { c } else { 0.0 });
        stats.add(glam::Vec3::from(kept));
    }
    film
}

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
    /// The image encoded in `format`; 8-bit formats use `transfer`. All but an EXR are the
    /// main image written as a film of one sample a pixel is ([`film_of`]): the same bytes a
    /// window shows of it.
    pub fn encode(&self, format: ImageFormat, transfer: Transfer) -> anyhow::Result<Vec<u8>> {
        match format {
            ImageFormat::Exr => self.encode_exr(),
            _ => encode_image(
                format,
                &film_of(self.width, self.height, &self.rgb),
                transfer,
            ),
        }
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
