//! The textures of a glTF file's materials as rt-gpu's: each image the file holds (in a .glb's
//! buffer, a data URI or a file beside it) decoded once, and each factor x texture product of
//! the spec (glTF 2.0, 3.9.2) a [`Texture::Image`] that shares the decoded texels and applies its
//! factor at lookup (an image used with many factors and samplers is held once).
//!
//! Read: a texture's image and `texCoord` (0 or 1), its sampler's wrap modes and magnification
//! filter (mipmaps are not built: a path tracer filters by taking many samples per pixel);
//! normal textures with their scale. `KHR_texture_transform` is applied to the mesh's texture
//! coordinates (`uv_sets`: one per set and material). Not read: TEXCOORD_2 and beyond.

use crate::assets::image::{self, Image};
use crate::assets::image_lookup::{Filter, ImageLookup, UvSet, Wrap};
use crate::assets::normal_map::NormalMap;
use crate::assets::texture::Texture;
use glam::Vec3;
use std::collections::HashMap;
use std::path::{Component, Path};
use std::sync::Arc;

/// A glTF file's images, decoded as its materials use them.
pub struct FileTextures<'a> {
    document: &'a gltf::Document,
    buffers: &'a [gltf::buffer::Data],
    /// The folder the file's relative URIs start from.
    base_dir: Option<&'a Path>,
    /// The file as the user named it, for messages.
    pub(super) source: &'a str,
    /// Images decoded, by (image index, whether decoded from sRGB).
    decoded: HashMap<(usize, bool), Arc<Image>>,
    /// Decoded images read with a sampler other than the default, by (image index, sRGB, how).
    sampled: HashMap<(usize, bool, ImageLookup), Arc<Image>>,
    /// Alpha channels of images, by (image index, how it is read); `None`: it has none.
    alphas: HashMap<(usize, ImageLookup), Option<Arc<Image>>>,
    /// Factor x image products, by (image index, sRGB, how it is read, the factor's bits).
    products: HashMap<(usize, bool, ImageLookup, [u32; 3]), Arc<Image>>,
}

impl<'a> FileTextures<'a> {
    pub fn new(
        document: &'a gltf::Document,
        buffers: &'a [gltf::buffer::Data],
        base_dir: Option<&'a Path>,
        source: &'a str,
    ) -> Self {
        FileTextures {
            document,
            buffers,
            base_dir,
            source,
            decoded: HashMap::new(),
            sampled: HashMap::new(),
            alphas: HashMap::new(),
            products: HashMap::new(),
        }
    }

    /// The file as the user named it, for messages.
    pub fn source(&self) -> &'a str {
        self.source
    }

    /// A colour texture (base colour, emission: sRGB) times `factor`, as `material` names
    /// it in `slot` (its glTF property name, for messages).
    pub fn colour(
        &mut self,
        info: &gltf::texture::Info,
        factor: Vec3,
        material: &str,
        slot: &str,
    ) -> Result<Texture, String> {
        let set = self.uv_set(set_of(info), material, slot)?;
        let index = info.texture().source().index();
        let image = self.sampled(&info.texture(), true, set)?;
        if factor == Vec3::ONE {
            return Ok(Texture::Image(image));
        }
        let key = (
            index,
            true,
            image.lookup,
            factor.to_array().map(f32::to_bits),
        );
        if let Some(product) = self.products.get(&key) {
            return Ok(Texture::Image(product.clone()));
        }
        let name = format!("{} x {factor}", image.source);
        let product = image.scaled(factor, &name)?.shared();
        self.products.insert(key, product.clone());
        Ok(Texture::Image(product))
    }

    /// A material's `normalTexture` (linear values) with its `scale`.
    pub fn normal_map(
        &mut self,
        normal: &gltf::material::NormalTexture,
        material: &str,
    ) -> Result<NormalMap, String> {
        let source = self.source;
        let set = self.uv_set(normal_set_of(normal), material, "normalTexture")?;
        let image = self.sampled(&normal.texture(), false, set)?;
        let map = NormalMap {
            image,
            scale: normal.scale(),
        };
        map.validate()
            .map_err(|e| format!("mesh {source}: material \"{material}\": {e}"))?;
        Ok(map)
    }

    /// The alpha channel of a material's base colour texture (linear), read as the texture's
    /// sampler says; `None` where its image has none.
    pub fn alpha(
        &mut self,
        info: &gltf::texture::Info,
        material: &str,
    ) -> Result<Option<Arc<Image>>, String> {
        let set = self.uv_set(set_of(info), material, "baseColorTexture")?;
        self.alpha_of(&info.texture(), set)
    }

    /// A texture of a material extension the `gltf` crate does not parse, from its JSON
    /// texture info (`slot`: its property name, for messages): its image decoded (from sRGB
    /// where `srgb`) and read as its sampler says; with `alpha`, the image's alpha channel
    /// instead (`None` where it has none: an alpha of 1 everywhere).
    pub fn extension_texture(
        &mut self,
        info: &serde_json::Value,
        srgb: bool,
        alpha: bool,
        material: &str,
        slot: &str,
    ) -> Result<Option<Arc<Image>>, String> {
        let source = self.source;
        let Some(index) = info.get("index").and_then(serde_json::Value::as_u64) else {
            return Err(format!(
                "mesh {source}: material \"{material}\"'s {slot} has no texture index"
            ));
        };
        let Some(texture) = usize::try_from(index)
            .ok()
            .and_then(|i| self.document.textures().nth(i))
        else {
            return Err(format!(
                "mesh {source}: material \"{material}\"'s {slot} names texture {index}, which does not exist"
            ));
        };
        let set = self.uv_set(json_set_of(info), material, slot)?;
        if alpha {
            return self.alpha_of(&texture, set);
        }
        self.sampled(&texture, srgb, set).map(Some)
    }

    /// The layers' image of `material` (`Pbr::layers`) from the textures that scale its clear
    /// coat's factor (red channel), its roughness (green) and its sheen's roughness (an alpha
    /// channel), where it has any: one image as wide and as tall as the widest and tallest, each
    /// resampled to it at its texels' centres where its size differs, 1 where a texture is
    /// absent. They must read one UV set (and so share its transform: `uv_sets`), and are read
    /// with the first's sampler.
    pub fn layers(
        &mut self,
        [coat, coat_roughness, sheen_roughness]: [Option<Arc<Image>>; 3],
        material: &str,
    ) -> Result<Option<Arc<Image>>, String> {
        let sources = [(coat, 0), (coat_roughness, 1), (sheen_roughness, 0)];
        let present = || sources.iter().filter_map(|(image, _)| image.as_ref());
        let Some(base) = present().next().cloned() else {
            return Ok(None);
        };
        if sources.iter().any(|(image, _)| {
            image
                .as_ref()
                .is_some_and(|i| i.lookup.uv_set != base.lookup.uv_set)
        }) {
            return Err(format!(
                "mesh {}: material \"{material}\"'s clear coat and sheen textures read different UV sets; rt-gpu reads them together from one",
                self.source
            ));
        }
        // Each side the largest's: a small texture beside a large one would otherwise lose the
        // large one's detail.
        let w = present().map(|i| i.width).max().unwrap_or(base.width);
        let h = present().map(|i| i.height).max().unwrap_or(base.height);
        let mut texels = Vec::with_capacity(3 * (w * h) as usize);
        for y in 0..h {
            for x in 0..w {
                for (image, channel) in &sources {
                    let value = match image {
                        None => 1.0,
                        Some(i) if (i.width, i.height) == (w, h) => i.texel(x, y)[*channel],
                        Some(i) => {
                            let uv = glam::Vec2::new(
                                (x as f32 + 0.5) / w as f32,
                                1.0 - (y as f32 + 0.5) / h as f32,
                            );
                            crate::assets::image_lookup::image_at(i, uv)[*channel]
                        }
                    };
                    texels.push(value);
                }
            }
        }
        let name = format!("{} (clear coat and sheen layers)", base.source);
        let merged = Image::from_linear(&name, w, h, texels)
            .map_err(|e| format!("mesh {}: {e}", self.source))?
            .with_lookup(base.lookup);
        Ok(Some(merged.shared()))
    }

    /// The alpha channel of `texture`'s image (linear) read at UV set `set` as its sampler
    /// says; `None` where the image has none.
    fn alpha_of(
        &mut self,
        texture: &gltf::Texture,
        set: UvSet,
    ) -> Result<Option<Arc<Image>>, String> {
        let index = texture.source().index();
        let lookup = lookup_of(&texture.sampler(), set);
        if let Some(image) = self.alphas.get(&(index, lookup)) {
            return Ok(image.clone());
        }
        let Some(file_image) = self.document.images().nth(index) else {
            return Err(format!(
                "mesh {}: a texture names image {index}, which does not exist",
                self.source
            ));
        };
        let name = format!("{} image {index}", self.source);
        let bytes = self.bytes(&file_image, &name)?;
        let image =
            image::decode_alpha_bytes(&bytes, &name)?.map(|a| a.with_lookup(lookup).shared());
        self.alphas.insert((index, lookup), image.clone());
        Ok(image)
    }

    /// A material's `metallicRoughnessTexture` (linear values: green roughness, blue metallic).
    pub fn metallic_roughness(
        &mut self,
        info: &gltf::texture::Info,
        material: &str,
    ) -> Result<Arc<Image>, String> {
        let set = self.uv_set(set_of(info), material, "metallicRoughnessTexture")?;
        self.sampled(&info.texture(), false, set)
    }

    /// The parameter image of a material whose transmissionTexture is `info`: its red channel
    /// the transmission texture's, its green and blue `metallic_roughness`'s (roughness and
    /// metallic; 1 where the material has none), read as `metallic_roughness` is (or as the
    /// transmission texture is, without one). The two must read one UV set, and so share its
    /// transform (`uv_sets`); where their images differ in size, the transmission texture is
    /// sampled at the other's texel centres.
    pub fn transmission(
        &mut self,
        info: &gltf::texture::Info,
        metallic_roughness: Option<Arc<Image>>,
        material: &str,
    ) -> Result<Arc<Image>, String> {
        let set = self.uv_set(set_of(info), material, "transmissionTexture")?;
        let transmission = self.sampled(&info.texture(), false, set)?;
        let base = metallic_roughness.as_ref().unwrap_or(&transmission);
        if base.lookup.uv_set != set {
            return Err(format!(
                "mesh {}: material \"{material}\"'s transmissionTexture and metallicRoughnessTexture read different UV sets; rt-gpu reads them together from one",
                self.source
            ));
        }
        let (w, h) = (base.width, base.height);
        let same_size = (transmission.width, transmission.height) == (w, h);
        let mut texels = Vec::with_capacity(3 * (w * h) as usize);
        for y in 0..h {
            for x in 0..w {
                let red = if same_size {
                    transmission.texel(x, y).x
                } else {
                    let uv = glam::Vec2::new(
                        (x as f32 + 0.5) / w as f32,
                        1.0 - (y as f32 + 0.5) / h as f32,
                    );
                    crate::assets::image_lookup::image_at(&transmission, uv).x
                };
                let [_, g, b] = match &metallic_roughness {
                    Some(mr) => mr.texel(x, y).to_array(),
                    None => [0.0, 1.0, 1.0],
                };
                texels.extend([red, g, b]);
            }
        }
        let name = format!("{} (transmission in red)", base.source);
        let merged = Image::from_linear(&name, w, h, texels)
            .map_err(|e| format!("mesh {}: {e}", self.source))?
            .with_lookup(base.lookup);
        Ok(merged.shared())
    }

    /// The UV set `material`'s `slot` reads (`set`, its texCoord); an error beyond the second.
    fn uv_set(&self, set: u32, material: &str, slot: &str) -> Result<UvSet, String> {
        uv_set(set).ok_or_else(|| {
            format!(
                "mesh {}: material \"{material}\"'s {slot} reads TEXCOORD_{set}; rt-gpu reads TEXCOORD_0 and TEXCOORD_1",
                self.source
            )
        })
    }

    /// `texture`'s image decoded (from sRGB where `srgb`) and read as its sampler says, at UV
    /// set `set`.
    fn sampled(
        &mut self,
        texture: &gltf::Texture,
        srgb: bool,
        set: UvSet,
    ) -> Result<Arc<Image>, String> {
        let index = texture.source().index();
        let image = self.image(index, srgb)?;
        let lookup = lookup_of(&texture.sampler(), set);
        if lookup == image.lookup {
            return Ok(image);
        }
        Ok(self
            .sampled
            .entry((index, srgb, lookup))
            .or_insert_with(|| image.with_lookup(lookup).shared())
            .clone())
    }

    /// Image `index` decoded (from sRGB where `srgb`), once.
    fn image(&mut self, index: usize, srgb: bool) -> Result<Arc<Image>, String> {
        if let Some(image) = self.decoded.get(&(index, srgb)) {
            return Ok(image.clone());
        }
        let source = self.source;
        let Some(file_image) = self.document.images().nth(index) else {
            return Err(format!(
                "mesh {source}: a texture names image {index}, which does not exist"
            ));
        };
        let name = match file_image.name() {
            Some(name) => format!("{source} image {index} (\"{}\")", super::file::quoted(name)),
            None => format!("{source} image {index}"),
        };
        let bytes = self.bytes(&file_image, &name)?;
        let image = image::decode_bytes(&bytes, &name, srgb)?.shared();
        self.decoded.insert((index, srgb), image.clone());
        Ok(image)
    }

    /// The encoded bytes of `file_image` (`name`: how messages name it).
    fn bytes(&self, file_image: &gltf::Image, name: &str) -> Result<Vec<u8>, String> {
        // glTF 2.0, 5.17: a `uri` or a `bufferView` with its `mimeType`, not both (the crate's
        // `source` unwraps them).
        let json = self.document.as_json().images.get(file_image.index());
        match json.map(|j| {
            (
                j.uri.is_some(),
                j.buffer_view.is_some(),
                j.mime_type.is_some(),
            )
        }) {
            Some((true, false, _)) | Some((false, true, true)) => {}
            Some((true, true, _)) => {
                return Err(format!(
                    "image {name} has both a uri and a bufferView; glTF allows one"
                ));
            }
            Some((false, true, false)) => {
                return Err(format!(
                    "image {name} lies in a bufferView without the mimeType glTF requires there"
                ));
            }
            _ => return Err(format!("image {name} has neither a uri nor a bufferView")),
        }
        match file_image.source() {
            gltf::image::Source::View { view, .. } => {
                let buffer = self.buffers.get(view.buffer().index()).map(|b| &b.0[..]);
                let range = view.offset()..view.offset().saturating_add(view.length());
                buffer
                    .and_then(|b| b.get(range))
                    .map(<[u8]>::to_vec)
                    .ok_or_else(|| format!("image {name}: its buffer view lies outside its buffer"))
            }
            gltf::image::Source::Uri { uri, .. } => match uri.strip_prefix("data:") {
                Some(data) => {
                    let Some((_, encoded)) = data.split_once(";base64,") else {
                        return Err(format!(
                            "image {name}: a data URI must be base64 (data:<type>;base64,...)"
                        ));
                    };
                    base64::decode(encoded)
                        .map_err(|e| format!("image {name}: its data URI is not base64: {e}"))
                }
                None => self.file_bytes(uri, name),
            },
        }
    }

    /// The bytes of the image file `uri` names: only a relative path that stays inside the
    /// glTF file's folder and names a regular file is opened.
    fn file_bytes(&self, uri: &str, name: &str) -> Result<Vec<u8>, String> {
        let relative = relative_uri(uri).map_err(|why| {
            format!(
                "image {name}: its URI \"{}\" {why}",
                super::file::quoted(uri)
            )
        })?;
        let path = match self.base_dir {
            Some(dir) => dir.join(&relative),
            None => Path::new(&relative).to_path_buf(),
        };
        let shown = beside(self.source, &relative);
        let (bytes, _) = crate::assets::inputs::read(&path, &shown, image::MAX_IMAGE_FILE_BYTES)
            .map_err(|e| {
                let relative = super::file::quoted(&relative);
                format!("cannot read image {name} ({relative}): {e}")
            })?;
        Ok(bytes)
    }
}

/// The relative path a glTF file's URI names (percent-decoded), or why it names none rt-gpu
/// opens: only paths that stay inside the file's folder (no absolute path, `..`, or scheme such
/// as `file://`), as glTF's URIs are relative to the file.
pub fn relative_uri(uri: &str) -> Result<String, String> {
    let relative = percent_decoded(uri).ok_or("is not valid UTF-8 once decoded")?;
    let path = Path::new(&relative);
    let scheme = relative
        .split_once(':')
        .is_some_and(|(s, _)| !s.is_empty() && !s.contains('/'));
    if relative.is_empty()
        || scheme
        || !path.components().all(|c| matches!(c, Component::Normal(_)))
    {
        return Err(
            "leaves the glTF file's folder (rt-gpu reads files beside it or below it)".into(),
        );
    }
    Ok(relative)
}

/// `relative`, a file beside `source` (a path as the user named it), as messages and film
/// identities name it.
pub fn beside(source: &str, relative: &str) -> String {
    Path::new(source)
        .parent()
        .unwrap_or(Path::new(""))
        .join(relative)
        .to_string_lossy()
        .into_owned()
}

/// glTF's UV coordinates (v down) as `KHR_texture_transform` maps them: scale, then rotate
/// (counter-clockwise in the image), then offset.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvTransform {
    pub offset: [f32; 2],
    pub rotation: f32,
    pub scale: [f32; 2],
}

impl UvTransform {
    pub const IDENTITY: UvTransform = UvTransform {
        offset: [0.0; 2],
        rotation: 0.0,
        scale: [1.0; 2],
    };

    /// `uv` (glTF's, v down) transformed, by the extension's matrix T R S.
    pub fn apply(&self, [u, v]: [f32; 2]) -> [f32; 2] {
        let (sin, cos) = self.rotation.sin_cos();
        let (su, sv) = (self.scale[0] * u, self.scale[1] * v);
        [
            cos * su + sin * sv + self.offset[0],
            -sin * su + cos * sv + self.offset[1],
        ]
    }
}

/// A UV set as rt-gpu holds it: glTF's `texCoord` 0 or 1, else `None`.
fn uv_set(set: u32) -> Option<UvSet> {
    match set {
        0 => Some(UvSet::First),
        1 => Some(UvSet::Second),
        _ => None,
    }
}

/// The UV set a texture reads: `KHR_texture_transform`'s `texCoord` where it gives one (the
/// extension overrides the texture's), else the texture's.
fn set_of(info: &gltf::texture::Info) -> u32 {
    (info.texture_transform().and_then(|t| t.tex_coord())).unwrap_or(info.tex_coord())
}

/// [`set_of`] of a normal texture (whose extensions the `gltf` crate gives only as JSON).
fn normal_set_of(normal: &gltf::material::NormalTexture) -> u32 {
    tex_coord_of_json(normal.extension_value("KHR_texture_transform")).unwrap_or(normal.tex_coord())
}

/// How a material reads one UV set: the `KHR_texture_transform` its textures on that set share
/// (rt-gpu applies it to the mesh's coordinates) and the first texture that reads it (for
/// messages).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvSetUse {
    pub transform: UvTransform,
    pub slot: &'static str,
}

/// How `material` reads TEXCOORD_0 and TEXCOORD_1 (`None`: no texture reads that set); an
/// error where a texture reads another set, or two on one set have different transforms.
pub fn uv_sets(material: &gltf::Material, source: &str) -> Result<[Option<UvSetUse>; 2], String> {
    let name = super::file::quoted(material.name().unwrap_or(""));
    let pbr = material.pbr_metallic_roughness();
    let infos = [
        ("baseColorTexture", pbr.base_color_texture()),
        ("metallicRoughnessTexture", pbr.metallic_roughness_texture()),
        ("emissiveTexture", material.emissive_texture()),
        (
            "transmissionTexture",
            material
                .transmission()
                .and_then(|t| t.transmission_texture()),
        ),
    ];
    let mut found: Vec<(&'static str, UvTransform, u32)> = infos
        .into_iter()
        .filter_map(|(slot, info)| {
            let info = info?;
            let t = info.texture_transform();
            let transform = t.as_ref().map_or(UvTransform::IDENTITY, |t| UvTransform {
                offset: t.offset(),
                rotation: t.rotation(),
                scale: t.scale(),
            });
            Some((slot, transform, set_of(&info)))
        })
        .collect();
    for (slot, info) in super::gltf_extensions::live_textures(material) {
        let transform = info
            .get("extensions")
            .and_then(|e| e.get("KHR_texture_transform"));
        found.push((slot, transform_of_json(transform), json_set_of(info)));
    }
    if let Some(normal) = material.normal_texture() {
        let value = normal.extension_value("KHR_texture_transform");
        found.push((
            "normalTexture",
            transform_of_json(value),
            normal_set_of(&normal),
        ));
    }
    let mut sets: [Option<UvSetUse>; 2] = [None; 2];
    for (slot, transform, set) in found {
        let Some(read) = uv_set(set) else {
            return Err(format!(
                "mesh {source}: material \"{name}\"'s {slot} reads TEXCOORD_{set}; rt-gpu reads TEXCOORD_0 and TEXCOORD_1"
            ));
        };
        let finite = transform
            .offset
            .iter()
            .chain(&transform.scale)
            .all(|x| x.is_finite())
            && transform.rotation.is_finite();
        if !finite {
            return Err(format!(
                "mesh {source}: material \"{name}\"'s {slot} has a KHR_texture_transform that is not finite: {transform:?}"
            ));
        }
        match &mut sets[read as usize] {
            Some(first) if first.transform != transform => {
                return Err(format!(
                    "mesh {source}: material \"{name}\"'s {} and {slot} read TEXCOORD_{set} with different KHR_texture_transforms ({:?} and {transform:?}); rt-gpu applies one per material and UV set",
                    first.slot, first.transform
                ));
            }
            Some(_) => {}
            empty => *empty = Some(UvSetUse { transform, slot }),
        }
    }
    Ok(sets)
}

/// A `KHR_texture_transform` read from its JSON (the `gltf` crate gives normal textures'
/// extensions only so); absent values take the extension's defaults.
fn transform_of_json(value: Option<&gltf::json::Value>) -> UvTransform {
    let Some(value) = value else {
        return UvTransform::IDENTITY;
    };
    let pair = |key: &str, default: [f32; 2]| {
        value
            .get(key)
            .and_then(|v| v.as_array())
            .filter(|a| a.len() == 2)
            .and_then(|a| Some([a[0].as_f64()? as f32, a[1].as_f64()? as f32]))
            .unwrap_or(default)
    };
    UvTransform {
        offset: pair("offset", [0.0; 2]),
        rotation: value
            .get("rotation")
            .and_then(|r| r.as_f64())
            .unwrap_or(0.0) as f32,
        scale: pair("scale", [1.0; 2]),
    }
}

/// [`set_of`] of a texture info given as JSON (a material extension's).
fn json_set_of(info: &serde_json::Value) -> u32 {
    let transform = info
        .get("extensions")
        .and_then(|e| e.get("KHR_texture_transform"));
    tex_coord_of_json(transform)
        .or_else(|| tex_coord_of_json(Some(info)))
        .unwrap_or(0)
}

fn tex_coord_of_json(value: Option<&gltf::json::Value>) -> Option<u32> {
    value?
        .get("texCoord")?
        .as_u64()
        .map(|t| t.min(u32::MAX as u64) as u32)
}

/// How a glTF sampler reads its image: its wrap modes, and its magnification filter (glTF
/// leaves an absent one to the renderer: linear, as Blender's importer takes it).
fn lookup_of(sampler: &gltf::texture::Sampler, uv_set: UvSet) -> ImageLookup {
    use gltf::texture::{MagFilter, WrappingMode};
    let wrap = |mode| match mode {
        WrappingMode::Repeat => Wrap::Repeat,
        WrappingMode::ClampToEdge => Wrap::Clamp,
        WrappingMode::MirroredRepeat => Wrap::Mirror,
    };
    ImageLookup {
        wrap_u: wrap(sampler.wrap_s()),
        wrap_v: wrap(sampler.wrap_t()),
        filter: match sampler.mag_filter() {
            Some(MagFilter::Nearest) => Filter::Nearest,
            _ => Filter::Linear,
        },
        uv_set,
    }
}

/// `uri` with its %XX escapes decoded (glTF URIs are URI-encoded: Blender writes a space as
/// %20); `None` if the result is not UTF-8.
fn percent_decoded(uri: &str) -> Option<String> {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        match (
            bytes[i],
            bytes.get(i + 1).copied().and_then(hex),
            bytes.get(i + 2).copied().and_then(hex),
        ) {
            (b'%', Some(hi), Some(lo)) => {
                out.push((hi * 16 + lo) as u8);
                i += 3;
            }
            (b, _, _) => {
                out.push(b);
                i += 1;
            }
        }
    }
    String::from_utf8(out).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uris_are_percent_decoded() {
        assert_eq!(percent_decoded("a%20b.png").as_deref(), Some("a b.png"));
        assert_eq!(
            percent_decoded("tex/w%C3%BCrfel.png").as_deref(),
            Some("tex/würfel.png")
        );
        assert_eq!(percent_decoded("100%.png").as_deref(), Some("100%.png"));
        assert_eq!(percent_decoded("%ff.png"), None);
    }
}
