//! Film files: a film's exact state in a multi-layer OpenEXR file that any viewer opens as the
//! image, and that rt-gpu reads back to continue a render (checkpoints) or to add renders of
//! other samples (shards, `rt-gpu merge`).
//!
//! Channels: `R`, `G`, `B` the mean radiance (f32); `variance.R/G/B` the variance of each mean
//! (f32, for the user); and the exact state as u32 words: `sum.<c>.<w>` and `odd_sum.<c>.<w>`
//! the words of the exact sums (`crate::shared::exact_sum`) that some pixel uses, `m2.<c>.lo/hi` the
//! bits of the f64 M2. The header attribute `rtgpu.film` says which render it is (scene digest
//! and every option that changes the image), which sample indices it holds, and the counts.
//! The sums, and so the mean, are bit-identical however a render was split; M2 (the variance of
//! independent samples) is merged in floating point and agrees to about 1e-12, not bit for bit.

use crate::film::{Film, PixelStats};
use crate::shared::exact_sum::{ExactSum, SUM_WORDS};
use anyhow::{Context, bail};
use exr::prelude::*;
use std::collections::HashMap;
use std::ops::Range;
use std::path::Path;

const CHANNELS: [&str; 3] = ["R", "G", "B"];
/// The header attribute holding a film's metadata, one `key=value` field a line.
const ATTR_FILM: &str = "rtgpu.film";
/// Format 2: exact sums in units of 2^-149, only their used words stored (`words=`); format 1
/// (older films: four words in units of 2^-32, metadata in four attributes) is still read.
const FORMAT: u32 = 2;
const FIELD_FORMAT: &str = "format";
const FIELD_IDENTITY: &str = "identity";
const FIELD_SAMPLES: &str = "samples";
const FIELD_COUNTS: &str = "counts";
const FIELD_WORDS: &str = "words";
const FIELD_DEVICE: &str = "device";
const LEGACY_IDENTITY: &str = "rtgpu.identity";
const LEGACY_SAMPLES: &str = "rtgpu.samples";
const LEGACY_COUNTS: &str = "rtgpu.counts";
const LEGACY_DEVICE: &str = "rtgpu.device";

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

/// The words of the exact sums that some pixel uses (all zero above and below), so that a film
/// stores only those: a render's radiance spans a few of the ten.
fn used_words(film: &Film) -> Range<usize> {
    let (mut lowest, mut highest) = (SUM_WORDS, 0);
    for p in &film.pixels {
        for sum in p.sum.iter().chain(&p.odd_sum) {
            for w in (0..SUM_WORDS).filter(|&w| sum.word(w) != 0) {
                lowest = lowest.min(w);
                highest = highest.max(w + 1);
            }
        }
    }
    if highest == 0 { 0..1 } else { lowest..highest }
}

/// `film` as a film file's bytes; without `meta`, an image any viewer reads but rt-gpu cannot
/// continue or merge. The same film and metadata give the same bytes.
pub fn encode(film: &Film, meta: Option<&FilmMeta>) -> anyhow::Result<Vec<u8>> {
    let pixels = &film.pixels;
    let (n, odd_n) = pixels.first().map_or((0, 0), |p| (p.n, p.odd_n));
    if pixels.iter().any(|p| (p.n, p.odd_n) != (n, odd_n)) {
        bail!("a film file needs the same samples in every pixel");
    }
    let used = used_words(film);
    let mut channels: Vec<AnyChannel<FlatSamples>> = Vec::new();
    let floats = |f: &dyn Fn(&PixelStats) -> f32| FlatSamples::F32(pixels.iter().map(f).collect());
    let words = |f: &dyn Fn(&PixelStats) -> u32| FlatSamples::U32(pixels.iter().map(f).collect());
    for (c, name) in CHANNELS.iter().enumerate() {
        channels.push(AnyChannel::new(*name, floats(&|p| p.mean()[c] as f32)));
        channels.push(AnyChannel::new(
            Text::from(format!("variance.{name}").as_str()),
            floats(&|p| film.variance_of_mean(p)[c] as f32),
        ));
        for w in used.clone() {
            channels.push(AnyChannel::new(
                Text::from(format!("sum.{name}.{w}").as_str()),
                words(&|p| p.sum[c].word(w)),
            ));
            channels.push(AnyChannel::new(
                Text::from(format!("odd_sum.{name}.{w}").as_str()),
                words(&|p| p.odd_sum[c].word(w)),
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
        if meta.spp() != n {
            bail!(
                "the film holds {n} samples per pixel, its ranges {}",
                format_ranges(&meta.samples)
            );
        }
        // One attribute: the exr crate writes several in hash-map order, which differs from
        // run to run, and a film's bytes should not.
        let fields = [
            (FIELD_FORMAT, FORMAT.to_string()),
            (FIELD_IDENTITY, meta.identity.clone()),
            (FIELD_SAMPLES, format_ranges(&meta.samples)),
            (
                FIELD_COUNTS,
                format!(
                    "spp={n} odd={odd_n} invalid={} stratified={}",
                    film.invalid_samples, film.stratified
                ),
            ),
            (FIELD_WORDS, format!("{}..{}", used.start, used.end)),
            (FIELD_DEVICE, meta.device.clone()),
        ];
        let text: Vec<String> = fields.iter().map(|(k, v)| format!("{k}={v}")).collect();
        attributes.other.insert(
            Text::from(ATTR_FILM),
            AttributeValue::Text(Text::from(text.join("\n").as_str())),
        );
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

/// The `key=value` fields of a film's metadata, from its one attribute (or, in films of older
/// versions, from one attribute each).
fn metadata_fields(
    shown: &std::path::Display,
    attributes: &LayerAttributes,
) -> anyhow::Result<HashMap<String, String>> {
    let text = |key: &str| match attributes.other.get(&Text::from(key)) {
        Some(AttributeValue::Text(t)) => Some(t.to_string()),
        _ => None,
    };
    if let Some(all) = text(ATTR_FILM) {
        let mut fields = HashMap::new();
        for line in all.lines() {
            let (k, v) = line
                .split_once('=')
                .with_context(|| format!("{shown}: bad {ATTR_FILM} line '{line}'"))?;
            fields.insert(k.to_string(), v.to_string());
        }
        return Ok(fields);
    }
    let mut fields = HashMap::from([(FIELD_FORMAT.to_string(), "1".to_string())]);
    for (key, field) in [
        (LEGACY_IDENTITY, FIELD_IDENTITY),
        (LEGACY_SAMPLES, FIELD_SAMPLES),
        (LEGACY_COUNTS, FIELD_COUNTS),
        (LEGACY_DEVICE, FIELD_DEVICE),
    ] {
        let value = text(key).with_context(|| {
            format!("{shown} is not an rt-gpu film file (no {key} attribute): only EXR files that rt-gpu rendered can be continued or merged")
        })?;
        fields.insert(field.to_string(), value);
    }
    Ok(fields)
}

/// Most sample ranges a film may list (shards and resumes join adjacent ranges; a film with more
/// is not one rt-gpu wrote).
pub const MAX_RANGES: usize = 4096;

/// Reads a film file written by rt-gpu (with its metadata), checking that what it says is
/// consistent: sizes, counts, sample ranges and every pixel's sums.
pub fn read(path: &Path) -> anyhow::Result<(Film, FilmMeta)> {
    let shown = path.display();
    // A FIFO or device named .exr would block or never end.
    let is_file = std::fs::metadata(path)
        .with_context(|| format!("cannot read the film file {shown}"))?
        .is_file();
    if !is_file {
        bail!("the film file {shown} is not a regular file");
    }
    let image = read_exr(path).with_context(|| format!("cannot read the film file {shown}"))?;
    let layer = match image.layer_data.as_slice() {
        [layer] => layer,
        _ => bail!("{shown} is not an rt-gpu film file: it has several layers"),
    };
    let fields = metadata_fields(&shown, &layer.attributes)?;
    let (meta, counts) = read_metadata(&shown, &fields)?;
    let film = read_pixels(&shown, layer, &fields, &meta, &counts)?;
    Ok((film, meta))
}

/// Metadata field `key` of the film file shown as `shown`, or an error naming what it lacks.
fn metadata_field<'a>(
    shown: &std::path::Display,
    fields: &'a HashMap<String, String>,
    key: &str,
) -> anyhow::Result<&'a str> {
    fields
        .get(key)
        .map(String::as_str)
        .with_context(|| format!("{shown}: its film metadata lacks {key}"))
}

/// A film file's format and what its counts say.
struct Counts {
    format: u32,
    /// Samples per pixel, and of those the odd-index ones.
    n: u64,
    odd_n: u64,
    invalid: u64,
    stratified: bool,
}

/// A film file's metadata fields, each checked, and checked against each other.
fn read_metadata(
    shown: &std::path::Display,
    fields: &HashMap<String, String>,
) -> anyhow::Result<(FilmMeta, Counts)> {
    let field = |key: &str| metadata_field(shown, fields, key);
    let format: u32 = field(FIELD_FORMAT)?
        .parse()
        .ok()
        .filter(|f| (1..=FORMAT).contains(f))
        .with_context(|| {
            format!(
                "{shown}: film format {} is not one this rt-gpu reads (1..={FORMAT})",
                fields[FIELD_FORMAT]
            )
        })?;
    let identity = field(FIELD_IDENTITY)?.to_string();
    let samples_text = field(FIELD_SAMPLES)?;
    if samples_text.matches(',').count() >= MAX_RANGES {
        bail!("{shown}: bad {FIELD_SAMPLES}: more than {MAX_RANGES} sample ranges");
    }
    let samples = parse_ranges(samples_text)
        .and_then(|r| check_disjoint_sorted(&r).map(|_| r))
        .map_err(|e| anyhow::anyhow!("{shown}: bad {FIELD_SAMPLES}: {e}"))?;
    let counts = field(FIELD_COUNTS)?;
    let device = field(FIELD_DEVICE)?.to_string();
    let count_fields: HashMap<&str, &str> = counts
        .split_whitespace()
        .filter_map(|f| f.split_once('='))
        .collect();
    let count = |key: &str| -> anyhow::Result<u64> {
        count_fields
            .get(key)
            .and_then(|v| v.parse().ok())
            .with_context(|| format!("{shown}: bad {FIELD_COUNTS} '{counts}': no {key}"))
    };
    let (n, odd_n, invalid) = (count("spp")?, count("odd")?, count("invalid")?);
    let stratified = count_fields.get("stratified") == Some(&"true");
    // Older films' samples were rounded to 2^-32 (and those above 2^32 dropped): they merge
    // and resume only with each other, not with exact ones (see `identity_difference`).
    let identity = if format == 1 {
        format!("{identity} {LEGACY_SUMS}")
    } else {
        identity
    };
    let meta = FilmMeta {
        identity,
        samples,
        device,
    };
    if meta.spp() != n {
        bail!(
            "{shown}: its sample ranges hold {} samples per pixel, its counts spp={n}",
            meta.spp()
        );
    }
    let odd_in_ranges: u64 = meta
        .samples
        .iter()
        .map(|r| (r.end as u64 / 2) - (r.start as u64 / 2))
        .sum();
    // Stratified films keep their odd-index samples' statistics, others none.
    let expected_odd = if stratified { odd_in_ranges } else { 0 };
    if odd_n != expected_odd {
        bail!(
            "{shown}: bad {FIELD_COUNTS}: odd={odd_n}, but a {} film of its sample ranges holds {expected_odd}",
            if stratified {
                "stratified"
            } else {
                "non-stratified"
            }
        );
    }
    let counts = Counts {
        format,
        n,
        odd_n,
        invalid,
        stratified,
    };
    Ok((meta, counts))
}

/// A film file's pixels: their exact sums (of the words `fields` says it holds) and M2, each
/// checked against the counts.
fn read_pixels(
    shown: &std::path::Display,
    layer: &Layer<AnyChannels<FlatSamples>>,
    fields: &HashMap<String, String>,
    meta: &FilmMeta,
    counts: &Counts,
) -> anyhow::Result<Film> {
    let Counts {
        format,
        n,
        odd_n,
        invalid,
        stratified,
    } = *counts;
    let field = |key: &str| metadata_field(shown, fields, key);
    let size = layer.size;
    let (width, height) = (size.0 as u32, size.1 as u32);
    crate::film::check_image_size(width, height).map_err(|e| anyhow::anyhow!("{shown}: {e}"))?;
    if let Some(claimed) = identity_field(&meta.identity, "size")
        && claimed != format!("{width}x{height}")
    {
        bail!("{shown}: its image is {width}x{height}, its identity says size={claimed}");
    }
    if invalid > n.saturating_mul(size.area() as u64) {
        bail!("{shown}: bad {FIELD_COUNTS}: invalid={invalid} exceeds its samples");
    }
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
    // Format 1 kept 4 words in units of 2^-32; format 2 the used words of the exact sums.
    let words: Range<usize> = if format == 1 {
        0..4
    } else {
        let text = field(FIELD_WORDS)?;
        text.split_once("..")
            .and_then(|(a, b)| Some(a.parse().ok()?..b.parse().ok()?))
            .filter(|r: &Range<usize>| !r.is_empty() && r.end <= SUM_WORDS)
            .with_context(|| format!("{shown}: bad {FIELD_WORDS} '{text}'"))?
    };
    let exact = |parts: &[&[u32]], i: usize| -> ExactSum {
        if format == 1 {
            let fixed = (0..4).fold(0u128, |s, w| s | (parts[w][i] as u128) << (32 * w));
            ExactSum::from_fixed(fixed, 32)
        } else {
            ExactSum::from_words((0..SUM_WORDS).map(|w| {
                if words.contains(&w) {
                    parts[w - words.start][i]
                } else {
                    0
                }
            }))
        }
    };
    let mut film = Film::new(width, height);
    film.invalid_samples = invalid;
    film.stratified = stratified;
    // No sum can exceed its count times the largest f32.
    let largest = |count: u64| count as f64 * f32::MAX as f64;
    for (c, name) in CHANNELS.iter().enumerate() {
        let sum: Vec<&[u32]> = words
            .clone()
            .map(|w| channel(&format!("sum.{name}.{w}")))
            .collect::<anyhow::Result<_>>()?;
        let odd: Vec<&[u32]> = words
            .clone()
            .map(|w| channel(&format!("odd_sum.{name}.{w}")))
            .collect::<anyhow::Result<_>>()?;
        let (lo, hi) = (
            channel(&format!("m2.{name}.lo"))?,
            channel(&format!("m2.{name}.hi"))?,
        );
        for (i, p) in film.pixels.iter_mut().enumerate() {
            p.n = n;
            p.odd_n = odd_n;
            p.sum[c] = exact(&sum, i);
            p.odd_sum[c] = exact(&odd, i);
            p.m2[c] = f64::from_bits(lo[i] as u64 | (hi[i] as u64) << 32);
            let (x, y) = (i % width as usize, i / width as usize);
            if p.sum[c].to_f64() > largest(n) {
                bail!(
                    "{shown}: sum.{name} of pixel ({x}, {y}) exceeds {n} samples of the largest radiance"
                );
            }
            if p.odd_sum[c].to_f64() > largest(odd_n) || p.sum[c].minus(&p.odd_sum[c]).is_none() {
                bail!("{shown}: odd_sum.{name} of pixel ({x}, {y}) exceeds what its samples allow");
            }
            if !(p.m2[c] >= 0.0 && p.m2[c].is_finite()) {
                bail!(
                    "{shown}: m2.{name} of pixel ({x}, {y}) is {}, not a finite non-negative number",
                    p.m2[c]
                );
            }
        }
    }
    Ok(film)
}

/// The backend the film file at `path` was rendered on, from its header alone (its pixels are
/// not read); `None` if it does not say.
pub fn recorded_backend(path: &Path) -> anyhow::Result<Option<crate::options::Backend>> {
    use crate::options::Backend;
    let shown = path.display();
    let meta = exr::meta::MetaData::read_from_file(path, false)
        .with_context(|| format!("cannot read the film file {shown}"))?;
    let Some(header) = meta.headers.first() else {
        return Ok(None);
    };
    let fields = metadata_fields(&shown, &header.own_attributes)?;
    let identity = fields.get(FIELD_IDENTITY).map_or("", String::as_str);
    Ok(match identity_field(identity, "backend") {
        Some("gpu") => Some(Backend::Gpu),
        Some("cpu") => Some(Backend::Cpu),
        _ => None,
    })
}

/// The value of `key=` in an identity, if it has one.
fn identity_field<'a>(identity: &'a str, key: &str) -> Option<&'a str> {
    identity
        .split_whitespace()
        .filter_map(|f| f.split_once('='))
        .find(|(k, _)| *k == key)
        .map(|(_, v)| v)
}

fn check_disjoint_sorted(ranges: &[Range<u32>]) -> std::result::Result<(), String> {
    for pair in ranges.windows(2) {
        if pair[1].start < pair[0].end {
            return Err(format!(
                "{}..{} and {}..{} are not sorted and disjoint",
                pair[0].start, pair[0].end, pair[1].start, pair[1].end
            ));
        }
    }
    Ok(())
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
///
/// `files` are the files the scene read, each `file:NAME=DIGEST` (`assets::inputs`), so that a
/// film of a scene whose texture or mesh changed since is told apart, naming the file.
pub fn identity(
    scene_digest: u64,
    files: &[String],
    backend: crate::options::Backend,
    opts: &crate::options::RenderOptions,
    everything_kernel: bool,
) -> String {
    let files: String = files.iter().map(|f| format!(" {f}")).collect();
    format!(
        "scene={scene_digest:016x} size={}x{} seed={} max_depth={} integrator={} sampler={} roulette_depth={} backend={} kernel={}{files}",
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

/// The prefix of an identity's fields that give a digest of a file the scene read.
pub const FILE_FIELD: &str = "file:";

/// The identity's field that gives the digest `hex` of a file the scene read, named `shown`.
pub fn file_field(shown: &str, hex: &str) -> String {
    format!("{FILE_FIELD}{}={hex}", identity_name(shown))
}

/// A file name as a film's identity writes it: one word, without `=` (percent-encoded).
fn identity_name(shown: &str) -> String {
    let mut out = String::with_capacity(shown.len());
    for c in shown.chars() {
        if c == '%' || c == '=' || c.is_whitespace() || c.is_control() {
            let mut buf = [0u8; 4];
            for b in c.encode_utf8(&mut buf).bytes() {
                out.push_str(&format!("%{b:02X}"));
            }
        } else {
            out.push(c);
        }
    }
    out
}

/// An [`identity_name`] as it was written (for messages: control characters stay escaped).
fn shown_name(identity_name: &str) -> String {
    let bytes = identity_name.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = bytes
            .get(i + 1..i + 3)
            .and_then(|h| std::str::from_utf8(h).ok())
            .and_then(|h| u8::from_str_radix(h, 16).ok());
        match (bytes[i], hex) {
            (b'%', Some(b)) if !(b as char).is_control() => {
                out.push(b);
                i += 3;
            }
            (b, _) => {
                out.push(b);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// What the identity of a film of format 1 (sums rounded to 2^-32) says of it when read.
const LEGACY_SUMS: &str = "sums=rounded";

/// Why two identities differ, naming the first setting that does ("seed 0 here, 7 there").
pub fn identity_difference(ours: &str, theirs: &str) -> Option<String> {
    if ours == theirs {
        return None;
    }
    let legacy = |s: &str| s.split_whitespace().any(|f| f == LEGACY_SUMS);
    if legacy(ours) != legacy(theirs) {
        return Some(
            "one was written by an older rt-gpu, whose sums were rounded (it merges only with films of that version: render the rest again)"
                .to_string(),
        );
    }
    let fields = |s: &str| -> Vec<(String, String)> {
        s.split_whitespace()
            .filter_map(|f| f.split_once('='))
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect()
    };
    let (ours, theirs) = (fields(ours), fields(theirs));
    // A file the scene reads that changed says more than the scene's digest, which holds it.
    let file = |key: &str| key.strip_prefix(FILE_FIELD).map(shown_name);
    for (key, value) in ours.iter().filter(|(k, _)| k.starts_with(FILE_FIELD)) {
        let name = file(key).unwrap_or_default();
        match theirs.iter().find(|(k, _)| k == key) {
            Some((_, v)) if v == value => continue,
            Some(_) => {
                return Some(format!(
                    "the scene's file {name} differs: its contents changed between the renders"
                ));
            }
            None => return Some(format!("it was not rendered from the scene's file {name}")),
        }
    }
    if let Some((key, _)) = theirs
        .iter()
        .find(|(k, _)| k.starts_with(FILE_FIELD) && !ours.iter().any(|(o, _)| o == k))
    {
        let name = file(key).unwrap_or_default();
        return Some(format!(
            "it was rendered from a file {name}, which this scene does not read"
        ));
    }
    for (key, value) in ours {
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
    if samples.len() > MAX_RANGES {
        bail!(
            "the merged film would hold {} separate sample ranges, more than the {MAX_RANGES} a film may: merge shards of adjacent samples",
            samples.len()
        );
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
    #[test]
    fn identity_names_are_one_word_and_read_back() {
        for name in ["tex.png", "my tex=1%.png", "a\nnote: forged", "ü/ß.png"] {
            let word = identity_name(name);
            assert!(!word.contains([' ', '=', '\n']), "{word}");
            let back = shown_name(&word);
            if name.contains('\n') {
                assert!(!back.contains('\n'), "{back}");
            } else {
                assert_eq!(back, name);
            }
        }
    }

    use super::*;
    use glam::{DVec3, Vec3};

    #[test]
    fn a_film_file_reads_back_exactly_and_an_image_without_metadata_is_refused() {
        let mut film = Film::new(3, 2);
        film.stratified = true;
        film.invalid_samples = 7;
        for (i, p) in film.pixels.iter_mut().enumerate() {
            // The sample indices the ranges below name.
            for s in [0u32, 1, 7, 8, 9] {
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

    fn small_film() -> (Film, FilmMeta) {
        let mut film = Film::new(3, 2);
        film.stratified = true;
        for (i, p) in film.pixels.iter_mut().enumerate() {
            for s in 0..4u32 {
                p.add_indexed(Vec3::new(1e-30 * (i + 1) as f32, 0.5, 1e30), s);
            }
        }
        let meta = FilmMeta {
            identity: "scene=0123 size=3x2 seed=4".to_string(),
            samples: std::iter::once(0..4).collect(),
            device: "test".to_string(),
        };
        (film, meta)
    }

    fn write_and_read(film: &Film, meta: &FilmMeta) -> anyhow::Result<(Film, FilmMeta)> {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("film.exr");
        std::fs::write(&path, encode(film, Some(meta)).expect("encodes")).expect("writes");
        read(&path)
    }

    #[test]
    fn film_bytes_are_deterministic_and_keep_any_radiance() {
        let (film, meta) = small_film();
        let first = encode(&film, Some(&meta)).expect("encodes");
        for _ in 0..4 {
            assert_eq!(encode(&film, Some(&meta)).expect("encodes"), first);
        }
        let (back, _) = write_and_read(&film, &meta).expect("reads");
        assert_eq!(back, film);
        assert_eq!(back.pixels[5].mean().x, 6e-30f32 as f64);
        assert_eq!(back.pixels[0].mean().z, 1e30f32 as f64);
    }

    #[test]
    fn inconsistent_films_are_refused_naming_the_field() {
        let (film, meta) = small_film();
        let refused = |film: &Film, meta: &FilmMeta, what: &str| {
            let err = format!("{:#}", write_and_read(film, meta).expect_err(what));
            assert!(err.contains(what), "{err}");
        };
        let mut wrong_size = meta.clone();
        wrong_size.identity = "scene=0123 size=4x4 seed=4".to_string();
        refused(&film, &wrong_size, "size=4x4");
        let mut odd_above = film.clone();
        odd_above.pixels[1].odd_sum[0] =
            odd_above.pixels[1].sum[0].plus(&ExactSum::from_words([1]));
        refused(&odd_above, &meta, "odd_sum.R of pixel (1, 0)");
        let mut bad_m2 = film.clone();
        bad_m2.pixels[2].m2.y = f64::NAN;
        refused(&bad_m2, &meta, "m2.G of pixel (2, 0)");
        let mut huge_sum = film.clone();
        huge_sum.pixels[0].sum[2] = ExactSum::from_words([u32::MAX; SUM_WORDS]);
        refused(&huge_sum, &meta, "sum.B of pixel (0, 0)");
        let mut too_many = film.clone();
        for p in &mut too_many.pixels {
            (p.n, p.odd_n) = (5000, 0);
        }
        let mut ranges = meta.clone();
        ranges.samples = (0..5000).map(|i| 2 * i..2 * i + 1).collect();
        refused(&too_many, &ranges, "more than 4096 sample ranges");
        let mut odd_count = film.clone();
        for p in &mut odd_count.pixels {
            p.odd_n = 3;
        }
        refused(&odd_count, &meta, "odd=3");
        let mut invalid = film.clone();
        invalid.invalid_samples = u64::MAX;
        refused(&invalid, &meta, "invalid=");
    }

    #[cfg(unix)]
    #[test]
    fn a_fifo_is_not_read_as_a_film() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("pipe.exr");
        let made = std::process::Command::new("mkfifo").arg(&path).status();
        if !made.is_ok_and(|s| s.success()) {
            return; // no mkfifo here
        }
        let err = format!("{:#}", read(&path).expect_err("a FIFO"));
        assert!(err.contains("not a regular file"), "{err}");
    }

    /// A film file as rt-gpu wrote them before format 2: four words per sum in units of 2^-32,
    /// metadata in four attributes. One pixel of 2 samples summing to 1.5 in every channel.
    fn format_1_film(path: &Path) {
        let words = |w: u32| FlatSamples::U32(vec![w]);
        let mut channels = Vec::new();
        for c in CHANNELS {
            channels.push(AnyChannel::new(c, FlatSamples::F32(vec![0.75])));
            let fixed = 3u128 << 31; // 1.5
            for w in 0..4 {
                let word = (fixed >> (32 * w)) as u32;
                channels.push(AnyChannel::new(
                    format!("sum.{c}.{w}").as_str(),
                    words(word),
                ));
                channels.push(AnyChannel::new(
                    format!("odd_sum.{c}.{w}").as_str(),
                    words(0),
                ));
            }
            channels.push(AnyChannel::new(format!("m2.{c}.lo").as_str(), words(0)));
            channels.push(AnyChannel::new(format!("m2.{c}.hi").as_str(), words(0)));
        }
        let mut attributes = LayerAttributes::default();
        for (key, value) in [
            (LEGACY_IDENTITY, "scene=0123 size=1x1 seed=0"),
            (LEGACY_SAMPLES, "0..2"),
            (LEGACY_COUNTS, "spp=2 odd=0 invalid=0 stratified=false"),
            (LEGACY_DEVICE, "old"),
        ] {
            attributes
                .other
                .insert(Text::from(key), AttributeValue::Text(Text::from(value)));
        }
        let layer = Layer::new(
            (1, 1),
            attributes,
            Encoding::FAST_LOSSLESS,
            AnyChannels::sort(channels.into()),
        );
        Image::from_layer(layer)
            .write()
            .to_file(path)
            .expect("writes");
    }

    #[test]
    fn older_films_read_exactly_and_merge_only_with_their_own() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("old.exr");
        format_1_film(&path);
        let (film, meta) = read(&path).expect("reads a format 1 film");
        assert_eq!(film.pixels[0].mean(), DVec3::splat(0.75));
        let ours = "scene=0123 size=1x1 seed=0";
        let why = identity_difference(ours, &meta.identity).expect("differs");
        assert!(why.contains("older rt-gpu"), "{why}");
        assert_eq!(identity_difference(&meta.identity, &meta.identity), None);
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
