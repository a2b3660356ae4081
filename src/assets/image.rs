//! Images that textures and environment lights read: decoded once per file into linear RGB f32
//! (looked up by `src/material/texture.rs` and `src/cpu/environment.rs`, twins in `shaders/`).
//!
//! A decoded image is shared: materials and backgrounds hold an `Arc<Image>`, and the same file
//! loaded again while one is held (the same path, size and modification time) is decoded once.
//! An image nothing holds any more is freed (a scene reloaded without it, a dropped scene).

use super::inputs::InputFile;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, OnceLock, Weak};

/// Longest image side accepted.
pub const MAX_IMAGE_SIDE: u32 = 16384;
/// Most memory one image's decoding may take (a 16384 x 8192 RGBA float image fits).
pub const MAX_DECODE_BYTES: u64 = 3 << 30;

/// A decoded image: `width` x `height` texels, linear RGB, row 0 at the top.
pub struct Image {
    /// The path as the scene file wrote it (scene files are written back with it).
    pub source: String,
    pub width: u32,
    pub height: u32,
    /// Three values per texel, row by row from the top, as decoded: shared by the copies that
    /// read it another way or scale it (glTF's factor x texture products), so that an image
    /// used by many materials is held once.
    pub texels: std::sync::Arc<[f32]>,
    /// What a surface's colour multiplies the texels by, per channel (1 but for glTF's
    /// factor x texture products): [`crate::material::texture::value`] and its twin
    /// `albedo_at` apply it; maps (normal, alpha, metallic-roughness) and environments read
    /// the texels as they are.
    pub factor: glam::Vec3,

    /// How a textured surface reads it beyond [0, 1] and between texels (an environment reads
    /// it its own way).
    pub lookup: super::image_lookup::ImageLookup,
    /// The largest value of each channel of `texels`, and their mean (without `factor`).
    channel_max: glam::Vec3,
    raw_mean: glam::Vec3,
    /// Built on first use by an environment light (see `assets::environment`).
    pub(crate) sampling: OnceLock<super::environment::Distribution>,
}

impl Image {
    /// An image from linear RGB values (three per texel, rows from the top); `source` names it.
    pub fn from_linear(
        source: &str,
        width: u32,
        height: u32,
        texels: Vec<f32>,
    ) -> Result<Self, String> {
        if width == 0 || height == 0 || width > MAX_IMAGE_SIDE || height > MAX_IMAGE_SIDE {
            return Err(format!(
                "image {source} is {width}x{height}: each side must be in 1..={MAX_IMAGE_SIDE}"
            ));
        }
        if texels.len() != 3 * width as usize * height as usize {
            return Err(format!("image {source}: wrong number of values"));
        }
        let mut max_value = glam::Vec3::ZERO;
        let mut sum = glam::DVec3::ZERO;
        for rgb in texels.chunks_exact(3) {
            sum += glam::DVec3::new(rgb[0] as f64, rgb[1] as f64, rgb[2] as f64);
        }
        for (i, &x) in texels.iter().enumerate() {
            if !(x.is_finite() && x >= 0.0) {
                let texel = i / 3;
                return Err(format!(
                    "image {source} has a value {x} at pixel ({}, {}): every value must be finite and non-negative",
                    texel % width as usize,
                    texel / width as usize
                ));
            }
            max_value[i % 3] = max_value[i % 3].max(x);
        }
        Ok(Image {
            source: source.to_string(),
            width,
            height,
            raw_mean: (sum / (width as f64 * height as f64)).as_vec3(),
            texels: texels.into(),
            factor: glam::Vec3::ONE,
            channel_max: max_value,
            lookup: Default::default(),
            sampling: OnceLock::new(),
        })
    }

    /// The largest value of any channel, times `factor` (albedo images must stay within 1).
    pub fn max_value(&self) -> f32 {
        self.max_channel().max_element()
    }

    /// The largest value of each channel, times `factor`.
    pub fn max_channel(&self) -> glam::Vec3 {
        self.channel_max * self.factor
    }

    /// The mean texel, times `factor` (what light picking weighs an image-textured emitter by).
    pub fn mean(&self) -> glam::Vec3 {
        self.raw_mean * self.factor
    }

    /// Texel (x, y) (x from the left, y from the top), as decoded: without `factor`.
    #[inline]
    pub fn texel(&self, x: u32, y: u32) -> glam::Vec3 {
        let i = 3 * (y as usize * self.width as usize + x as usize);
        let rgb = &self.texels[i..i + 3];
        glam::Vec3::new(rgb[0], rgb[1], rgb[2])
    }

    /// This image with every texel multiplied by `factor` channel by channel (glTF's factor x
    /// texture products), named `source`: its texels shared, the factor applied at lookup.
    pub fn scaled(&self, factor: glam::Vec3, source: &str) -> Result<Self, String> {
        let factor = self.factor * factor;
        if !(factor.is_finite() && factor.min_element() >= 0.0) {
            return Err(format!(
                "image {source}: its factor {factor} must be finite and non-negative"
            ));
        }
        Ok(Image {
            source: source.to_string(),
            texels: self.texels.clone(),
            factor,
            sampling: OnceLock::new(),
            ..*self
        })
    }

    /// A copy of this image read with `lookup` (its texels shared).
    pub fn with_lookup(&self, lookup: super::image_lookup::ImageLookup) -> Self {
        Image {
            source: self.source.clone(),
            texels: self.texels.clone(),
            lookup,
            sampling: OnceLock::new(),
            ..*self
        }
    }

    /// `self`, to be held by the materials and backgrounds that read it.
    pub fn shared(self) -> Arc<Image> {
        Arc::new(self)
    }
}

impl std::fmt::Debug for Image {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        write!(f, "Image({}, {}x{})", self.source, self.width, self.height)
    }
}

impl PartialEq for Image {
    fn eq(&self, other: &Self) -> bool {
        std::ptr::eq(self, other)
            || (self.width == other.width
                && self.height == other.height
                && self.lookup == other.lookup
                && self.factor == other.factor
                && self.texels == other.texels)
    }
}

/// sRGB-encoded value in [0, 1] to linear.
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Reads the image at `path` (PNG, JPEG, OpenEXR or Radiance HDR): 8- and 16-bit images are
/// decoded from sRGB, floating-point ones are linear; alpha is ignored. `source` is the path as
/// the scene wrote it. Errors are one line naming the file.
pub fn load(path: &Path, source: &str) -> Result<Arc<Image>, String> {
    load_as(path, source, true)
}

/// A file as it was when decoded (its path, size and modification time), and its encoding.
type FileVersion = (PathBuf, u64, std::time::SystemTime, bool);

/// The images decoded from files, while something holds them: a file loaded again (by another
/// scene, or the viewer's reload) while its image is held is not decoded again, and an image
/// nothing holds is freed.
static FILES: OnceLock<Mutex<Held>> = OnceLock::new();

/// Each file's image while held, and the file as read (for the film's record of inputs).
type Held = HashMap<FileVersion, (Weak<Image>, InputFile)>;

/// [`load`], with 8- and 16-bit values taken as sRGB only where `srgb` (colours), else as
/// linear (data such as normal maps). Each file is decoded once per encoding; the file is
/// recorded as one the scene reads (`inputs`), on a cache hit too.
pub fn load_as(path: &Path, source: &str, srgb: bool) -> Result<Arc<Image>, String> {
    let meta = std::fs::metadata(path).map_err(|e| format!("cannot read image {source}: {e}"))?;
    if !meta.is_file() {
        return Err(format!("image {source} is not a file"));
    }
    let canonical = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
    let modified = meta.modified().unwrap_or(std::time::UNIX_EPOCH);
    let key = (canonical, meta.len(), modified, srgb);
    let cache = FILES.get_or_init(Default::default);
    let held = cache
        .lock()
        .map_err(|_| "image cache poisoned")?
        .get(&key)
        .and_then(|(image, input)| Some((image.upgrade()?, input.clone())));
    if let Some((image, input)) = held {
        // As this scene names it (another may have named it otherwise).
        super::inputs::note(&InputFile {
            shown: source.to_string(),
            ..input
        });
        return Ok(image);
    }
    let (bytes, input) = super::inputs::read(path, source, MAX_IMAGE_FILE_BYTES)
        .map_err(|e| format!("cannot read image {source}: {e}"))?;
    let image = decode_file(bytes, source, srgb)?.shared();
    let mut cache = cache.lock().map_err(|_| "image cache poisoned")?;
    // Images no scene holds any more are gone: so are their entries.
    cache.retain(|_, (image, _)| image.strong_count() > 0);
    cache.insert(key, (Arc::downgrade(&image), input));
    Ok(image)
}

/// How many decoded image files are held (by scenes, materials, backgrounds) at present: what
/// a reloaded scene frees shows here.
pub fn files_held() -> usize {
    let cache = FILES.get_or_init(Default::default);
    let cache = cache
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    cache
        .values()
        .filter(|(image, _)| image.strong_count() > 0)
        .count()
}

/// Largest image file read (a path may name anything): an uncompressed RGBA f32 OpenEXR of the
/// most texels an image may have ([`MAX_TEXELS`]) takes 2 GiB.
pub const MAX_IMAGE_FILE_BYTES: u64 = 4 << 30;

/// Most texels an image may have: a 16384x8192 environment (the largest common HDRI), which
/// takes 1.6 GB as linear f32 RGB.
pub const MAX_TEXELS: u64 = 1 << 27;

/// Bytes a texel may take at the peak of loading an image (decoded, converted to linear RGB
/// f32 and, for an environment, its sampling tables built in f64): checked against the memory
/// available from the image's header, before anything is decoded.
const PEAK_BYTES_PER_TEXEL: u64 = 64;

/// A Radiance HDR file, whose first line is `#?` and the writing program's name: the `image`
/// crate reads only `#?RADIANCE`, so others (Mitsuba and many tools write `#?RGBE`) are given
/// that line. `Err` gives back the bytes of a file of another format.
fn radiance_hdr(mut bytes: Vec<u8>, source: &str) -> Result<Result<Vec<u8>, Vec<u8>>, String> {
    if !bytes.starts_with(b"#?") {
        return Ok(Err(bytes));
    }
    let header_end = bytes.windows(2).take(1 << 16).position(|w| w == b"\n\n");
    let Some(header_end) = header_end else {
        return Err(format!(
            "image {source}: its Radiance HDR header is truncated (no blank line ends it)"
        ));
    };
    let resolution = bytes[header_end + 2..]
        .split(|&b| b == b'\n')
        .next()
        .map(String::from_utf8_lossy)
        .unwrap_or_default();
    let words: Vec<&str> = resolution.split_whitespace().collect();
    if words.len() != 4 || words[1].parse::<u32>().is_err() || words[3].parse::<u32>().is_err() {
        return Err(format!(
            "image {source}: its Radiance HDR file has no size line after its header (such as -Y 512 +X 1024)"
        ));
    }
    let first_line = bytes.iter().position(|&b| b == b'\n').unwrap_or(0);
    if &bytes[..first_line] != b"#?RADIANCE" {
        bytes.splice(..first_line, b"#?RADIANCE".iter().copied());
    }
    Ok(Ok(bytes))
}

/// What the device a scene is loaded for says of an image of so many texels: `Err` with why it
/// cannot hold it. Installed by [`with_device_check`].
pub type DeviceCheck = std::sync::Arc<dyn Fn(u64) -> Result<(), String> + Send + Sync>;

/// The check of the device the scene being loaded is for (process-wide, as the threads that
/// read a scene's material libraries load its images too).
static DEVICE_CHECK: Mutex<Option<DeviceCheck>> = Mutex::new(None);

/// Runs `f` (a scene's loading) with every image it decodes checked from its header against
/// the device that will hold it (`--backend gpu`: the kernel's image texture), so that an
/// image the device cannot hold is refused before a decode of gigabytes and seconds.
pub fn with_device_check<R>(check: DeviceCheck, f: impl FnOnce() -> R) -> R {
    /// Puts the previous check back, however `f` ends.
    struct Restore(Option<DeviceCheck>);
    impl Drop for Restore {
        fn drop(&mut self) {
            *DEVICE_CHECK.lock().unwrap_or_else(|p| p.into_inner()) = self.0.take();
        }
    }
    let previous = DEVICE_CHECK
        .lock()
        .unwrap_or_else(|p| p.into_inner())
        .replace(check);
    let _restore = Restore(previous);
    f()
}

/// Refuses an image whose header says it is too large for this machine's memory, or for the
/// device the scene is loaded for.
fn check_size_before_decoding((width, height): (u32, u32), source: &str) -> Result<(), String> {
    if width > MAX_IMAGE_SIDE || height > MAX_IMAGE_SIDE {
        return Err(format!(
            "image {source} is {width}x{height}: each side must be at most {MAX_IMAGE_SIDE} pixels"
        ));
    }
    let texels = width as u64 * height as u64;
    if texels > MAX_TEXELS {
        return Err(format!(
            "image {source} is {width}x{height}: more than the {MAX_TEXELS} texels (16384x8192) an image may have (use a smaller image)"
        ));
    }
    let device = DEVICE_CHECK
        .lock()
        .unwrap_or_else(|p| p.into_inner())
        .clone();
    if let Some(check) = device {
        check(texels).map_err(|why| format!("image {source} is {width}x{height}: {why}"))?;
    }
    crate::film::check_available(texels * PEAK_BYTES_PER_TEXEL, || {
        format!("image {source} is {width}x{height}: loading it")
    })
    .map_err(|e| format!("{e} (use a smaller image)"))
}

/// Decodes an image file's `bytes` (by their format, not the file's name).
fn decode_file(bytes: Vec<u8>, source: &str, srgb: bool) -> Result<Image, String> {
    let decoded = match radiance_hdr(bytes, source)? {
        Ok(bytes) => decode_from(
            image::ImageReader::with_format(std::io::Cursor::new(bytes), image::ImageFormat::Hdr),
            source,
        )?,
        Err(bytes) => {
            let reader = image::ImageReader::new(std::io::Cursor::new(bytes))
                .with_guessed_format()
                .map_err(|e| format!("cannot read image {source}: {}", one_line(&e)))?;
            decode_from(reader, source)?
        }
    };
    to_linear(decoded, source, srgb)
}

/// Decodes an image held in memory (one embedded in a glTF file, say) as [`load`] decodes a
/// file, except that 8- and 16-bit values are taken as sRGB only where `srgb` (glTF's colour
/// textures), else as linear (its metallic-roughness and normal textures).
pub fn decode_bytes(bytes: &[u8], source: &str, srgb: bool) -> Result<Image, String> {
    let reader = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| format!("cannot read image {source}: {}", one_line(&e)))?;
    to_linear(decode_from(reader, source)?, source, srgb)
}

/// The alpha channel of the image in `bytes` (PNG, JPEG, ...) as a linear image with alpha in
/// each channel; `None` if it has no alpha channel (everywhere opaque).
pub fn decode_alpha_bytes(bytes: &[u8], source: &str) -> Result<Option<Image>, String> {
    let reader = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| format!("cannot read image {source}: {}", one_line(&e)))?;
    let decoded = decode_from(reader, source)?;
    if !decoded.color().has_alpha() {
        return Ok(None);
    }
    let (width, height) = (decoded.width(), decoded.height());
    let texels = (decoded.into_rgba32f().into_raw().chunks_exact(4))
        .flat_map(|rgba| [rgba[3]; 3])
        .collect();
    Image::from_linear(&format!("{source} (alpha)"), width, height, texels).map(Some)
}

/// A decoded image's linear RGB: floating-point values as they are, others from sRGB where
/// `srgb`.
fn to_linear(decoded: image::DynamicImage, source: &str, srgb: bool) -> Result<Image, String> {
    let float = matches!(
        decoded.color(),
        image::ColorType::Rgb32F | image::ColorType::Rgba32F
    );
    let (width, height) = (decoded.width(), decoded.height());
    let mut texels = decoded.into_rgb32f().into_raw();
    if !float && srgb {
        for x in &mut texels {
            *x = srgb_to_linear(*x);
        }
    }
    Image::from_linear(source, width, height, texels)
}

fn one_line(e: &dyn std::fmt::Display) -> String {
    e.to_string().replace('\n', " ")
}

/// Decodes what `reader` reads, within the decoder's limits, once its header has been checked
/// (`check_size_before_decoding`).
fn decode_from<R: std::io::BufRead + std::io::Seek>(
    mut reader: image::ImageReader<R>,
    source: &str,
) -> Result<image::DynamicImage, String> {
    use image::ImageDecoder;
    if reader.format().is_none() {
        return Err(format!(
            "image {source}: unknown format (rt-gpu reads PNG, JPEG, OpenEXR and Radiance HDR)"
        ));
    }
    let limits = || {
        let mut limits = image::Limits::default();
        limits.max_image_width = Some(MAX_IMAGE_SIDE);
        limits.max_image_height = Some(MAX_IMAGE_SIDE);
        limits.max_alloc = Some(MAX_DECODE_BYTES);
        limits
    };
    reader.limits(limits());
    let error = |e: image::ImageError| match e {
        image::ImageError::Unsupported(u) => format!(
            "image {source}: unsupported ({}; rt-gpu reads PNG, JPEG, OpenEXR and Radiance HDR)",
            one_line(&u)
        ),
        image::ImageError::Limits(l)
            if matches!(l.kind(), image::error::LimitErrorKind::DimensionError) =>
        {
            format!(
                "image {source} is too large: each side must be at most {MAX_IMAGE_SIDE} pixels"
            )
        }
        image::ImageError::Limits(_) => format!(
            "image {source} is too large to decode (the decoder's memory limit is {} MB)",
            MAX_DECODE_BYTES >> 20
        ),
        other => format!("cannot decode image {source}: {}", one_line(&other)),
    };
    let decoder = reader.into_decoder().map_err(error)?;
    check_size_before_decoding(decoder.dimensions(), source)?;
    // As `ImageReader::decode` does: the decoded buffer must fit the allocation limit.
    limits().reserve(decoder.total_bytes()).map_err(error)?;
    image::DynamicImage::from_decoder(decoder).map_err(error)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_decoding_matches_the_standard() {
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-6);
        assert!((srgb_to_linear(0.5) - 0.21404).abs() < 1e-4);
        assert!((srgb_to_linear(0.04) - 0.04 / 12.92).abs() < 1e-7);
    }

    #[test]
    fn bad_values_are_refused() {
        let err =
            Image::from_linear("x.exr", 2, 1, vec![0.0, 1.0, f32::NAN, 0.0, 0.0, 0.0]).unwrap_err();
        assert!(err.contains("x.exr") && err.contains("(0, 0)"), "{err}");
        let err =
            Image::from_linear("y.exr", 2, 1, vec![0.0, 1.0, 0.0, 0.0, -1.0, 0.0]).unwrap_err();
        assert!(err.contains("(1, 0)"), "{err}");
        assert!(Image::from_linear("z", 0, 1, vec![]).is_err());
    }
}
