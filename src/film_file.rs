//! Film files: a film's exact state in a multi-layer OpenEXR file that any viewer opens as the
//! image, and that rt-gpu reads back to continue a render (checkpoints) or to add renders of
//! other samples (shards, `rt-gpu merge`).
//!
//! Channels: `R`, `G`, `B` the mean radiance (f32); `variance.R/G/B` the variance of each mean
//! (f32, for the user); and the exact state as u32 words: `sum.<c>.0..3` and `odd_sum.<c>.0..3`
//! the fixed-point sums (least significant word first), `m2.<c>.lo/hi` the bits of the f64 M2.
//! Header attributes `rtgpu.*` say which render it is (scene digest and every option that
//! changes the image), which sample indices it holds, and the counts.

use crate::film::{Film, PixelStats};
use anyhow::{Context, bail};
use exr::prelude::*;
use std::collections::HashMap;
use std::ops::Range;
use std::path::Path;

const CHANNELS: [&str; 3] = ["R", "G", "B"];
const ATTR_IDENTITY: &str = "rtgpu.identity";
const ATTR_SAMPLES: &str = "rtgpu.samples";
const ATTR_COUNTS: &str = "rtgpu.counts";
const ATTR_DEVICE: &str = "rtgpu.device";

/// What a film file says about the render its samples came from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FilmMeta {
    /// The scene's digest and every option that changes the image: films merge, and
    /// checkpoints resume, only with an equal identity.
    pub identity: String,
    /// The sample indices of every pixel, as sorted disjoint ranges.
    pub samples: Vec<Range<u32>>,
    /// What rendered it (for the record: any device's samples merge).
    pub device: String,
}

impl FilmMeta {
    /// Samples per pixel the ranges hold.
    pub fn spp(&self) -> u64 {
        self.samples.iter().map(|r| (r.end - r.start) as u64).sum()
    }
}

/// Sample ranges as text: `0..64,128..256`.
pub fn format_ranges(ranges: &[Range<u32>]) -> String {
    let parts: Vec<String> = ranges
        .iter()
        .map(|r| format!("{}..{}", r.start, r.end))
        .collect();
    parts.join(",")
}

/// One range `FIRST..END` (END exclusive, greater than FIRST).
pub fn parse_range(text: &str) -> std::result::Result<Range<u32>, String> {
    let bad = || format!("expected sample indices FIRST..END such as 0..256, got '{text}'");
    let (a, b) = text.split_once("..").ok_or_else(bad)?;
    let (a, b): (u32, u32) = (
        a.trim().parse().map_err(|_| bad())?,
        b.trim().parse().map_err(|_| bad())?,
    );
    if b <= a {
        return Err(format!(
            "the sample range {a}..{b} is empty (END must exceed FIRST)"
        ));
    }
    Ok(a..b)
}

fn parse_ranges(text: &str) -> std::result::Result<Vec<Range<u32>>, String> {
    if text.is_empty() {
        return Ok(Vec::new());
    }
    text.split(',').map(parse_range).collect()
}

/// `film` as a film file's bytes; without `meta`, an image any viewer reads but rt-gpu cannot
/// continue or merge.
pub fn encode(film: &Film, meta: Option<&FilmMeta>) -> anyhow::Result<Vec<u8>> {
    let pixels = &film.pixels;
    let (n, odd_n) = pixels.first().map_or((0, 0), |p| (p.n, p.odd_n));
    if pixels.iter().any(|p| (p.n, p.odd_n) != (n, odd_n)) {
        bail!("a film file needs the same samples in every pixel");
    }
    let mut channels: Vec<AnyChannel<FlatSamples>> = Vec::new();
    let floats = |f: &dyn Fn(&PixelStats) -> f32| FlatSamples::F32(pixels.iter().map(f).collect());
    let words = |f: &dyn Fn(&PixelStats) -> u32| FlatSamples::U32(pixels.iter().map(f).collect());
    for (c, name) in CHANNELS.iter().enumerate() {
        channels.push(AnyChannel::new(*name, floats(&|p| p.mean()[c] as f32)));
        channels.push(AnyChannel::new(
            Text::from(format!("variance.{name}").as_str()),
            floats(&|p| film.variance_of_mean(p)[c] as f32),
        ));
        for w in 0..4 {
            channels.push(AnyChannel::new(
                Text::from(format!("sum.{name}.{w}").as_str()),
                words(&|p| (p.sum[c] >> (32 * w)) as u32),
            ));
            channels.push(AnyChannel::new(
                Text::from(format!("odd_sum.{name}.{w}").as_str()),
                words(&|p| (p.odd_sum[c] >> (32 * w)) as u32),
            ));
        }
        channels.push(AnyChannel::new(
            Text::from(format!("m2.{name}.lo").as_str()),
            words(&|p| p.m2[c].to_bits() as u32),
        ));
        channels.push(AnyChannel::new(
            Text::from(format!("m2.{name}.hi").as_str()),
            words(&|p| (p.m2[c].to_bits() >> 32) as u32),
        ));
    }
    let mut attributes = LayerAttributes::default();
    if let Some(meta) = meta {
        let text = |s: &str| AttributeValue::Text(Text::from(s));
        let counts = format!(
            "spp={n} odd={odd_n} invalid={} stratified={}",
            film.invalid_samples, film.stratified
        );
        if meta.spp() != n {
            bail!(
                "the film holds {n} samples per pixel, its ranges {}",
                format_ranges(&meta.samples)
            );
        }
        for (key, value) in [
            (ATTR_IDENTITY, meta.identity.as_str()),
            (ATTR_SAMPLES, &format_ranges(&meta.samples)),
            (ATTR_COUNTS, &counts),
            (ATTR_DEVICE, &meta.device),
        ] {
            attributes.other.insert(Text::from(key), text(value));
        }
    }
    let layer = Layer::new(
        (film.width as usize, film.height as usize),
        attributes,
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(channels.into()),
    );
    let mut out = std::io::Cursor::new(Vec::new());
    Image::from_layer(layer).write().to_buffered(&mut out)?;
    Ok(out.into_inner())
}

/// Reads a film file written by rt-gpu (with its metadata).
pub fn read(path: &Path) -> anyhow::Result<(Film, FilmMeta)> {
    let shown = path.display();
    let image = read_exr(path).with_context(|| format!("cannot read the film file {shown}"))?;
    let layer = match image.layer_data.as_slice() {
        [layer] => layer,
        _ => bail!("{shown} is not an rt-gpu film file: it has several layers"),
    };
    let attr = |key: &str| -> anyhow::Result<String> {
        match layer.attributes.other.get(&Text::from(key)) {
            Some(AttributeValue::Text(t)) => Ok(t.to_string()),
            _ => bail!(
                "{shown} is not an rt-gpu film file (no {key} attribute): only EXR files that rt-gpu rendered can be continued or merged"
            ),
        }
    };
    let identity = attr(ATTR_IDENTITY)?;
    let samples = parse_ranges(&attr(ATTR_SAMPLES)?)
        .map_err(|e| anyhow::anyhow!("{shown}: bad {ATTR_SAMPLES}: {e}"))?;
    let counts = attr(ATTR_COUNTS)?;
    let device = attr(ATTR_DEVICE)?;
    let fields: HashMap<&str, &str> = counts
        .split_whitespace()
        .filter_map(|f| f.split_once('='))
        .collect();
    let count = |key: &str| -> anyhow::Result<u64> {
        fields
            .get(key)
            .and_then(|v| v.parse().ok())
            .with_context(|| format!("{shown}: bad {ATTR_COUNTS} attribute '{counts}'"))
    };
    let (n, odd_n, invalid) = (count("spp")?, count("odd")?, count("invalid")?);
    let stratified = fields.get("stratified") == Some(&"true");

    let size = layer.size;
    let (width, height) = (size.0 as u32, size.1 as u32);
    crate::film::check_image_size(width, height).map_err(|e| anyhow::anyhow!("{shown}: {e}"))?;
    let channel = |name: &str| -> anyhow::Result<&[u32]> {
        let found = layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name == *name)
            .with_context(|| format!("{shown} lacks the film channel {name}"))?;
        match &found.sample_data {
            FlatSamples::U32(values) if values.len() == size.area() => Ok(values),
            _ => bail!("{shown}: the film channel {name} is not u32 samples of the image"),
        }
    };
    let mut film = Film::new(width, height);
    film.invalid_samples = invalid;
    film.stratified = stratified;
    for (c, name) in CHANNELS.iter().enumerate() {
        let sum: Vec<&[u32]> = (0..4)
            .map(|w| channel(&format!("sum.{name}.{w}")))
            .collect::<anyhow::Result<_>>()?;
        let odd: Vec<&[u32]> = (0..4)
            .map(|w| channel(&format!("odd_sum.{name}.{w}")))
            .collect::<anyhow::Result<_>>()?;
        let (lo, hi) = (
            channel(&format!("m2.{name}.lo"))?,
            channel(&format!("m2.{name}.hi"))?,
        );
        let wide = |words: &[&[u32]], i: usize| {
            (0..4).fold(0u128, |s, w| s | (words[w][i] as u128) << (32 * w))
        };
        for (i, p) in film.pixels.iter_mut().enumerate() {
            p.n = n;
            p.odd_n = odd_n;
            p.sum[c] = wide(&sum, i);
            p.odd_sum[c] = wide(&odd, i);
            p.m2[c] = f64::from_bits(lo[i] as u64 | (hi[i] as u64) << 32);
        }
    }
    let meta = FilmMeta {
        identity,
        samples,
        device,
    };
    if meta.spp() != n {
        bail!("{shown}: its sample ranges and its sample count disagree");
    }
    Ok((film, meta))
}

fn read_exr(path: &Path) -> anyhow::Result<Image<Layers<AnyChannels<FlatSamples>>>> {
    Ok(exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_file(path)?)
}

/// A render's identity as a film file records it: the scene's digest and every option that
/// changes its samples (not the sample range: that is what checkpoints and shards differ in).
pub fn identity(
    scene_digest: u64,
    backend: crate::options::Backend,
    opts: &crate::options::RenderOptions,
    everything_kernel: bool,
) -> String {
    format!(
        "scene={scene_digest:016x} size={}x{} seed={} max_depth={} integrator={} sampler={} roulette_depth={} backend={} kernel={}",
        opts.width,
        opts.height,
        opts.seed,
        opts.max_depth,
        opts.integrator.name(),
        opts.sampler.name(),
        opts.roulette_depth,
        backend.name(),
        if everything_kernel {
            "everything"
        } else {
            "specialised"
        }
    )
}

/// Why two identities differ, naming the first setting that does ("seed 0 here, 7 there").
pub fn identity_difference(ours: &str, theirs: &str) -> Option<String> {
    if ours == theirs {
        return None;
    }
    let fields = |s: &str| -> Vec<(String, String)> {
        s.split_whitespace()
            .filter_map(|f| f.split_once('='))
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect()
    };
    let theirs = fields(theirs);
    for (key, value) in fields(ours) {
        match theirs.iter().find(|(k, _)| *k == key) {
            Some((_, v)) if *v == value => continue,
            Some((_, v)) => {
                let what = if key == "scene" {
                    "the scene differs".to_string()
                } else {
                    format!("{key} is {value} here, {v} there")
                };
                return Some(what);
            }
            None => return Some(format!("it has no {key}")),
        }
    }
    Some("its settings differ".to_string())
}

/// A film read from somewhere a message can name.
pub struct NamedFilm {
    pub name: String,
    pub film: Film,
    pub meta: FilmMeta,
}

/// Films of disjoint samples of one render, added up.
pub struct Combined {
    pub film: Film,
    pub meta: FilmMeta,
    /// Sample indices below the last one that no film held.
    pub missing: Vec<Range<u32>>,
}

/// Adds up films of one render (equal identities and sizes) whose samples do not overlap: the
/// exact sums in any order give the same image; M2 is merged in sample order, so that the result
/// does not depend on the order `films` come in either.
pub fn combine(mut films: Vec<NamedFilm>) -> anyhow::Result<Combined> {
    let Some(first) = films.first() else {
        bail!("no films to merge");
    };
    for other in &films[1..] {
        if let Some(why) = identity_difference(&first.meta.identity, &other.meta.identity) {
            bail!(
                "{} and {} are films of different renders ({why}): only samples of one render merge",
                first.name,
                other.name
            );
        }
        if (other.film.width, other.film.height) != (first.film.width, first.film.height) {
            bail!("{} and {} differ in size", first.name, other.name);
        }
    }
    films.sort_by_key(|f| f.meta.samples.first().map_or(0, |r| r.start));
    let mut ranges: Vec<(Range<u32>, &str)> = films
        .iter()
        .flat_map(|f| f.meta.samples.iter().map(|r| (r.clone(), f.name.as_str())))
        .collect();
    ranges.sort_by_key(|(r, _)| r.start);
    for pair in ranges.windows(2) {
        let ((a, a_name), (b, b_name)) = (&pair[0], &pair[1]);
        if b.start < a.end {
            bail!(
                "{a_name} (samples {}..{}) and {b_name} (samples {}..{}) overlap: each sample may be merged once",
                a.start,
                a.end,
                b.start,
                b.end
            );
        }
    }
    // The union, with adjacent ranges joined, and what it lacks below its end.
    let mut samples: Vec<Range<u32>> = Vec::new();
    for (r, _) in &ranges {
        match samples.last_mut() {
            Some(last) if last.end == r.start => last.end = r.end,
            _ => samples.push(r.clone()),
        }
    }
    let mut missing = Vec::new();
    let mut next = 0;
    for r in &samples {
        if r.start > next {
            missing.push(next..r.start);
        }
        next = r.end;
    }
    let mut films = films.into_iter();
    let first = films.next().context("no films to merge")?;
    let (mut film, identity) = (first.film, first.meta.identity);
    let mut devices = vec![first.meta.device];
    for other in films {
        film.merge(&other.film);
        if !devices.contains(&other.meta.device) {
            devices.push(other.meta.device);
        }
    }
    let meta = FilmMeta {
        identity,
        samples,
        device: devices.join(" + "),
    };
    Ok(Combined {
        film,
        meta,
        missing,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn a_film_file_reads_back_exactly_and_an_image_without_metadata_is_refused() {
        let mut film = Film::new(3, 2);
        film.stratified = true;
        film.invalid_samples = 7;
        for (i, p) in film.pixels.iter_mut().enumerate() {
            for s in 0..5u32 {
                let v = 1e-3 * (i as f32 + 1.0) * (s as f32 + 0.5);
                p.add_indexed(Vec3::new(v, 3.0e9, 0.0), s);
            }
        }
        let meta = FilmMeta {
            identity: "scene=0123 seed=4".to_string(),
            samples: vec![0..2, 7..10],
            device: "test".to_string(),
        };
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("film.exr");
        std::fs::write(&path, encode(&film, Some(&meta)).expect("encodes")).expect("writes");
        let (read_film, read_meta) = read(&path).expect("reads");
        assert_eq!(read_film, film);
        assert_eq!(read_meta, meta);

        std::fs::write(&path, encode(&film, None).expect("encodes")).expect("writes");
        let err = read(&path).expect_err("no metadata").to_string();
        assert!(err.contains("not an rt-gpu film file"), "{err}");
    }

    #[test]
    fn identities_name_what_differs() {
        let ours = "scene=00ff seed=0 sampler=sobol";
        assert_eq!(identity_difference(ours, ours), None);
        let why = identity_difference(ours, "scene=00ff seed=3 sampler=sobol");
        assert_eq!(why.as_deref(), Some("seed is 0 here, 3 there"));
        let why = identity_difference(ours, "scene=11ff seed=0 sampler=sobol");
        assert_eq!(why.as_deref(), Some("the scene differs"));
    }
}
