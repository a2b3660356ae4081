//! Scene files: TOML, human-writable, documented in `scenes/README.md`.
//!
//! Numbers are checked as they are read (finite, in range), so a bad value is reported at its own
//! line and column; whole-object checks (a zero-area quad, a degenerate camera) report the line of
//! the table they belong to.

use super::punctual::Punctual;
use super::{
    Background, Camera, Material, Object, RenderDefaults, Scene, SceneError, Shape, Transform,
};
use crate::assets::loader::Loader;
use crate::params::{Colour, Num, V3};
use glam::Vec3;
use serde::{Deserialize, Deserializer, Serialize};
use std::collections::BTreeMap;
use std::ops::Range;
use std::path::Path;
use std::sync::Arc;
use toml::Spanned;

pub use crate::film::MAX_IMAGE_SIDE;
/// Longest path a scene or the CLI may ask for.
pub const MAX_DEPTH_LIMIT: u32 = 10_000;

/// A scene file problem, located in its file.
#[derive(Debug, thiserror::Error)]
#[error("{file}:{line}:{column}: {message}")]
pub struct SceneFileError {
    pub file: String,
    pub line: usize,
    pub column: usize,
    pub message: String,
}

/// Reads and checks the scene file at `path`.
pub fn load(path: &Path) -> anyhow::Result<Scene> {
    let bytes = std::fs::read(path)
        .map_err(|e| anyhow::anyhow!("cannot read scene file {}: {e}", path.display()))?;
    let file = path.display().to_string();
    let text = std::str::from_utf8(&bytes).map_err(|e| {
        let (line, column) = line_and_column(&bytes[..e.valid_up_to()]);
        SceneFileError {
            file: file.clone(),
            line,
            column,
            message: "the file is not valid UTF-8 text here".into(),
        }
    })?;
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into());
    // Paths in the file are relative to its directory.
    let loader = Loader::for_file(path);
    let (scene, inputs) =
        crate::assets::inputs::recorded(|| parse_with(&loader, text, &file, &name));
    Ok(Scene { inputs, ..scene? })
}

/// 1-based line and column (in characters) of the end of `before`.
fn line_and_column(before: &[u8]) -> (usize, usize) {
    let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
    let start = before
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |i| i + 1);
    let column = String::from_utf8_lossy(&before[start..]).chars().count() + 1;
    (line, column)
}

/// Most characters of a user's text (a name, a line) quoted in a message.
const MAX_QUOTED_CHARS: usize = 60;

/// `text` as quoted in a message: cut short if it is long.
/// Control characters (a newline that would forge a second line of output) are escaped.
pub(crate) fn quoted(text: &str) -> String {
    let escaped = |s: &str| -> String {
        s.chars()
            .map(|c| {
                if c.is_control() {
                    c.escape_default().to_string()
                } else {
                    c.to_string()
                }
            })
            .collect()
    };
    if text.chars().count() <= MAX_QUOTED_CHARS {
        return escaped(text);
    }
    let head: String = text.chars().take(MAX_QUOTED_CHARS).collect();
    format!(
        "{}... ({} characters)",
        escaped(&head),
        text.chars().count()
    )
}

/// Parses scene-file text; `file` names it in errors. The files it names are relative to the
/// working directory (see [`parse_with`]).
pub fn parse(text: &str, file: &str, name: &str) -> Result<Scene, SceneFileError> {
    parse_with(&Loader::working_directory(), text, file, name)
}

/// Parses scene-file text, reading the images and meshes it names through `loader`; `file`
/// names it in errors.
pub fn parse_with(
    loader: &Loader,
    text: &str,
    file: &str,
    name: &str,
) -> Result<Scene, SceneFileError> {
    // Serde reaches the loader from the material readers (see `assets::loader`).
    loader.during(|| parse_in(loader, text, file, name))
}

fn parse_in(loader: &Loader, text: &str, file: &str, name: &str) -> Result<Scene, SceneFileError> {
    let located = |span: Option<Range<usize>>, message: String| {
        let mut offset = span.map(|s| s.start).unwrap_or(0).min(text.len());
        while !text.is_char_boundary(offset) {
            offset -= 1;
        }
        let (line, column) = line_and_column(&text.as_bytes()[..offset]);
        SceneFileError {
            file: file.to_string(),
            line,
            column,
            message,
        }
    };
    // Where a parser error is, with the line it is in when that helps.
    let toml_error = |e: toml::de::Error, base: usize| {
        // A required top-level table that is absent has no place in the text: say which.
        if let Some(field) = e
            .message()
            .strip_prefix("missing field `")
            .and_then(|m| m.split('`').next())
            && e.span().is_none_or(|s| s.start == 0)
            && base == 0
        {
            let what = if field == "camera" {
                "the scene has no [camera] table (a top-level table: see scenes/README.md)"
                    .to_string()
            } else {
                format!("the scene lacks `{field}` at its top level")
            };
            return located(Some(0..0), what);
        }
        let span = e.span().map(|s| s.start + base..s.end + base);
        let source_line = span
            .as_ref()
            .and_then(|s| {
                text[..s.start.min(text.len())]
                    .rfind('\n')
                    .map(|i| i + 1)
                    .or(Some(0))
            })
            .and_then(|start| text[start..].lines().next())
            .map(str::trim)
            .filter(|l| !l.is_empty())
            .map(|l| format!(" (in `{}`)", quoted(l)))
            .unwrap_or_default();
        let message = quoted_message(e.message());
        located(span, format!("{message}{source_line}"))
    };
    let doc = match object_chunks(text) {
        Some((header_end, starts)) => {
            // Large scenes are mostly [[object]] tables: parsed one by one, a 50 MB file
            // takes a fraction of the time and memory the whole document's parse tree needs.
            let mut doc: SceneDoc =
                toml::from_str(&text[..header_end]).map_err(|e| toml_error(e, 0))?;
            if doc.objects.is_empty() {
                for (i, &start) in starts.iter().enumerate() {
                    let end = starts.get(i + 1).copied().unwrap_or(text.len());
                    let part: ObjectsOnly =
                        toml::from_str(&text[start..end]).map_err(|e| toml_error(e, start))?;
                    doc.objects.extend(part.objects.into_iter().map(|o| {
                        let object = shifted(o, start);
                        let span = object.span();
                        let mut object = object.into_inner();
                        object.translate = object.translate.map(|t| shifted(t, start));
                        Spanned::new(span, object)
                    }));
                }
                doc
            } else {
                toml::from_str(text).map_err(|e| toml_error(e, 0))?
            }
        }
        None => toml::from_str(text).map_err(|e| toml_error(e, 0))?,
    };
    doc.into_scene(loader, name)
        .map_err(|(span, message)| located(span, message))
}

/// Writes `scene` as scene-file text that [`parse`] reads back to the same scene.
pub fn to_toml(scene: &Scene) -> String {
    let doc = SceneDoc::from_scene(scene);
    let body = toml::to_string(&doc).unwrap_or_else(|e| format!("# cannot serialise: {e}\n"));
    format!(
        "# rt-gpu scene \"{}\" (format: scenes/README.md)\n\n{body}",
        scene.name
    )
}

/// A digest of `scene` as its file would write it (FNV-1a over the text) and of what the files
/// it reads hold, for the identity of its films: the scene's settings and materials serialised once, then each object on its own,
/// so that time grows with the object count (toml serialises a whole document in time
/// quadratic in its tables).
pub fn digest(scene: &Scene) -> u64 {
    let mut doc = SceneDoc::from_scene(scene);
    let objects = std::mem::take(&mut doc.objects);
    let mut hash = Fnv::default();
    hash.add(&toml::to_string(&doc).unwrap_or_default());
    for object in &objects {
        hash.add("\n[[object]]\n");
        hash.add(&toml::to_string(object.get_ref()).unwrap_or_default());
    }
    // What the files it reads hold, not only their names.
    for input in &scene.inputs {
        hash.add(&format!("\n{} {}", input.shown, input.hex_digest()));
    }
    hash.0
}

/// The FNV-1a hash of the text added to it.
struct Fnv(u64);

impl Default for Fnv {
    fn default() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv {
    fn add(&mut self, text: &str) {
        for b in text.bytes() {
            self.0 = (self.0 ^ b as u64).wrapping_mul(0x0100_0000_01b3);
        }
    }
}

/// Where each top-level `[[object]]` table starts, and where the text before the first one
/// ends, when the text can be cut there into documents that parse to the same tables: no
/// multi-line strings (which could hold such a line), and after the first object only object
/// tables and their sub-tables. `None` means: parse the text whole.
fn object_chunks(text: &str) -> Option<(usize, Vec<usize>)> {
    if text.contains("'''") || text.contains("\"\"\"") {
        return None;
    }
    let mut starts = Vec::new();
    let mut offset = 0;
    for line in text.split_inclusive('\n') {
        let trimmed = line.trim_start();
        if trimmed.starts_with('[') {
            let is_object = trimmed.strip_prefix("[[object]]").is_some_and(|rest| {
                rest.trim_start().is_empty() || rest.trim_start().starts_with('#')
            });
            if is_object {
                starts.push(offset);
            } else if !starts.is_empty() && !trimmed.starts_with("[object.") {
                return None;
            }
        }
        offset += line.len();
    }
    let header_end = *starts.first()?;
    Some((header_end, starts))
}

/// `value` with its span moved `by` bytes: from a chunk of the text to the whole text.
fn shifted<T>(value: Spanned<T>, by: usize) -> Spanned<T> {
    let span = value.span();
    Spanned::new(span.start + by..span.end + by, value.into_inner())
}

/// A run of `[[object]]` tables on their own.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ObjectsOnly {
    #[serde(default, rename = "object")]
    objects: Vec<Spanned<ObjectDoc>>,
}

/// `[[light]]`: one of `point = { position, intensity }`, `spot = { position, look_at,
/// intensity, inner, outer }` (cone half-angles in degrees), `directional = { direction,
/// irradiance }` (the direction light travels). Radiometric: W/sr, W/m^2.
#[derive(Deserialize, Serialize, Default)]
#[serde(deny_unknown_fields)]
struct LightDoc {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    point: Option<PointDoc>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    spot: Option<SpotDoc>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    directional: Option<DirectionalDoc>,
}

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct PointDoc {
    position: V3,
    intensity: V3,
}

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct SpotDoc {
    position: V3,
    look_at: V3,
    intensity: V3,
    inner: Num,
    outer: Num,
}

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct DirectionalDoc {
    direction: V3,
    irradiance: V3,
}

impl LightDoc {
    fn light(self) -> Result<Punctual, String> {
        let light = match (self.point, self.spot, self.directional) {
            (Some(p), None, None) => Punctual::Point {
                position: p.position.vec(),
                intensity: p.intensity.vec(),
            },
            (None, Some(s), None) => Punctual::Spot {
                position: s.position.vec(),
                direction: (s.look_at.vec().as_dvec3() - s.position.vec().as_dvec3())
                    .normalize_or_zero()
                    .as_vec3(),
                intensity: s.intensity.vec(),
                inner: s.inner.0.to_radians(),
                outer: s.outer.0.to_radians(),
            },
            (None, None, Some(d)) => Punctual::Directional {
                // In f64: a direction of tiny components, [1e-30, -1e-30, 0] say, is one.
                direction: d.direction.vec().as_dvec3().normalize_or_zero().as_vec3(),
                irradiance: d.irradiance.vec(),
            },
            _ => {
                return Err(
                    "a [[light]] is one of point = {...}, spot = {...} or directional = {...}"
                        .into(),
                );
            }
        };
        light.validate()?;
        Ok(light)
    }

    fn from_light(light: &Punctual) -> LightDoc {
        match *light {
            Punctual::Point {
                position,
                intensity,
            } => LightDoc {
                point: Some(PointDoc {
                    position: V3::from(position),
                    intensity: V3::from(intensity),
                }),
                ..Default::default()
            },
            Punctual::Spot {
                position,
                direction,
                intensity,
                inner,
                outer,
            } => LightDoc {
                spot: Some(SpotDoc {
                    position: V3::from(position),
                    look_at: V3::from(position + direction),
                    intensity: V3::from(intensity),
                    inner: Num(inner.to_degrees()),
                    outer: Num(outer.to_degrees()),
                }),
                ..Default::default()
            },
            Punctual::Directional {
                direction,
                irradiance,
            } => LightDoc {
                directional: Some(DirectionalDoc {
                    direction: V3::from(direction),
                    irradiance: V3::from(irradiance),
                }),
                ..Default::default()
            },
        }
    }
}

/// A punctual light as a scene file's `[[light]]` table writes it (`point = { position,
/// intensity }`, `spot = {...}` or `directional = {...}`). A spot's `look_at` lies as far along
/// its direction as its position is from the origin (at least 1), so that reading the table
/// back gives its direction to f32's precision wherever it stands (one unit away, a position
/// far out would round the direction, or the look-at onto the position).
pub fn light_table(light: &Punctual) -> Result<toml::Value, String> {
    let mut doc = LightDoc::from_light(light);
    if let (
        Punctual::Spot {
            position,
            direction,
            ..
        },
        Some(spot),
    ) = (*light, &mut doc.spot)
    {
        let reach = position.abs().max_element().max(1.0);
        spot.look_at = V3::from(position + direction * reach);
    }
    toml::Value::try_from(doc).map_err(|e| e.to_string())
}

/// The punctual light a `[[light]]` table describes, checked as a scene file's are.
pub fn light_from_table(table: toml::Value) -> Result<Punctual, String> {
    let doc: LightDoc = table
        .try_into()
        .map_err(|e: toml::de::Error| quoted_message(e.message()))?;
    doc.light()
}

/// A parser message on one line, with any long quoted text in it cut short.
fn quoted_message(message: &str) -> String {
    let flat = message.trim().replace('\n', " ");
    if flat.chars().count() <= 4 * MAX_QUOTED_CHARS {
        return flat;
    }
    quoted(&flat).replacen(
        &format!("... ({} characters)", flat.chars().count()),
        "...",
        1,
    )
}

// ---- The document ---------------------------------------------------------------------------

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct SceneDoc {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    render: Option<RenderDoc>,
    camera: Spanned<CameraDoc>,
    #[serde(default)]
    materials: BTreeMap<String, Spanned<Material>>,
    #[serde(default, rename = "object")]
    objects: Vec<Spanned<ObjectDoc>>,
    #[serde(default, rename = "light", skip_serializing_if = "Vec::is_empty")]
    lights: Vec<Spanned<LightDoc>>,
}

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct RenderDoc {
    width: Option<Spanned<u32>>,
    height: Option<Spanned<u32>>,
    max_depth: Option<Spanned<u32>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    background: Option<Spanned<BackgroundDoc>>,
}

#[derive(Serialize)]
#[serde(untagged)]
enum BackgroundDoc {
    Colour(Colour),
    Named(String),
    Environment(EnvironmentDoc),
}

/// `{ image = "sky.hdr", strength = 1, rotate_y = 0 }`.
#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct EnvironmentDoc {
    image: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    strength: Option<Num>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    rotate_y: Option<Num>,
}

/// A colour `[r, g, b]`, `"sky"` or an environment image, with one message for anything else
/// (serde's untagged enums say only that nothing matched).
impl<'de> Deserialize<'de> for BackgroundDoc {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        let expected = "background must be a colour [r, g, b], \"sky\" or { image = \"file\", strength, rotate_y }";
        match toml::Value::deserialize(d)? {
            toml::Value::String(name) if name == "sky" => Ok(BackgroundDoc::Named(name)),
            toml::Value::String(name) => Err(D::Error::custom(format!(
                "{expected}, got \"{}\"",
                quoted(&name)
            ))),
            value @ toml::Value::Array(_) => Colour::deserialize(value)
                .map(BackgroundDoc::Colour)
                .map_err(|e| D::Error::custom(format!("{expected}: {}", e.message()))),
            value @ toml::Value::Table(_) => EnvironmentDoc::deserialize(value)
                .map(BackgroundDoc::Environment)
                .map_err(|e| D::Error::custom(format!("background: {}", e.message()))),
            other => Err(D::Error::custom(format!("{expected}, got {other}"))),
        }
    }
}

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct CameraDoc {
    /// A camera of a glTF file the scene places, by name: its placement and field of view.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    gltf: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    look_from: Option<V3>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    look_at: Option<V3>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    up: Option<V3>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    vfov: Option<Num>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    aperture: Option<Num>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    focus_distance: Option<Num>,
}

/// Defines `ObjectDoc`, an `[[object]]` table, with a key per shape of `shape::with_shapes!`
/// (its file's name), and its conversions to and from those shapes.
macro_rules! object_doc {
    ($($module:ident :: $ty:ident ($params:ident) => $array:ident,)+) => {
        /// (Its `Spanned` fields are moved to whole-text positions in `parse`: add new ones there.)
        #[derive(Default, Deserialize, Serialize)]
        #[serde(deny_unknown_fields)]
        struct ObjectDoc {
            $(
                #[serde(default, skip_serializing_if = "Option::is_none")]
                $module: Option<crate::shape::$params>,
            )+
            #[serde(default, rename = "box", skip_serializing_if = "Option::is_none")]
            cuboid: Option<BoxDoc>,
            #[serde(default, skip_serializing_if = "Option::is_none")]
            mesh: Option<MeshDoc>,
            /// A mesh's scale: a number or [x, y, z], applied before rotation and translation.
            #[serde(default, skip_serializing_if = "Option::is_none")]
            scale: Option<ScaleDoc>,
            /// Optional only for a glTF mesh, whose own materials are used without it.
            #[serde(default, skip_serializing_if = "Option::is_none")]
            material: Option<String>,
            #[serde(default, skip_serializing_if = "Option::is_none")]
            rotate_y: Option<Num>,
            #[serde(default, skip_serializing_if = "Option::is_none")]
            translate: Option<Spanned<V3>>,
        }

        impl ObjectDoc {
            /// The shapes of `crate::shape` it names.
            fn surfaces(&self) -> Vec<Shape> {
                let mut out = Vec::new();
                $(if let Some(p) = self.$module {
                    out.push(Shape::Surface(crate::shape::SurfaceParams::$ty(p)));
                })+
                out
            }

            /// Names `params` as its shape.
            fn set_surface(&mut self, params: crate::shape::SurfaceParams) {
                match params {
                    $(crate::shape::SurfaceParams::$ty(p) => self.$module = Some(p),)+
                }
            }
        }
    };
}
crate::shape::with_shapes!(object_doc);

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct MeshDoc {
    file: String,
    /// A glTF node (with its children) by name.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    node: Option<String>,
    /// One of the file's parts (a material's triangles), as rt-gpu writes scenes back; all
    /// without it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    part: Option<u32>,
}

#[derive(Clone, Copy, Serialize)]
#[serde(untagged)]
enum ScaleDoc {
    Uniform(Num),
    PerAxis(V3),
}

impl<'de> Deserialize<'de> for ScaleDoc {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        match toml::Value::deserialize(d)? {
            value @ toml::Value::Array(_) => V3::deserialize(value)
                .map(ScaleDoc::PerAxis)
                .map_err(|e| D::Error::custom(format!("scale: {}", e.message()))),
            value => Num::deserialize(value).map(ScaleDoc::Uniform).map_err(|e| {
                D::Error::custom(format!(
                    "scale must be a number or [x, y, z]: {}",
                    e.message()
                ))
            }),
        }
    }
}

impl ScaleDoc {
    fn vec(self) -> Vec3 {
        match self {
            ScaleDoc::Uniform(n) => Vec3::splat(n.0),
            ScaleDoc::PerAxis(v) => v.vec(),
        }
    }
}

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct BoxDoc {
    min: V3,
    max: V3,
}

type Located = (Option<Range<usize>>, String);

/// The index of the material a scene file names, or an error listing the names it has.
fn lookup_material(index: &BTreeMap<String, u32>, name: &str) -> Result<u32, String> {
    if let Some(&material) = index.get(name) {
        return Ok(material);
    }
    let known: Vec<String> = index.keys().take(20).map(|k| quoted(k)).collect();
    let more = index.len().saturating_sub(known.len());
    let more = if more > 0 {
        format!(" and {more} more")
    } else {
        String::new()
    };
    Err(format!(
        "unknown material \"{}\" (defined: {}{more})",
        quoted(name),
        known.join(", ")
    ))
}

impl SceneDoc {
    fn into_scene(self, loader: &Loader, name: &str) -> Result<Scene, Located> {
        let defaults = render_defaults(self.render.as_ref())?;
        let background = background(loader, self.render.and_then(|r| r.background))?;
        let mut materials = SceneMaterials::new(self.materials)?;
        let mut objects = Vec::new();
        let mut object_spans = Vec::new();
        // Every part of the mesh files read, for the parse: objects that each place one part
        // of a file (`part = N`) then share the file read once, and its parts instance.
        let mut read = Vec::new();
        for spanned in self.objects {
            let span = Some(spanned.span());
            // A mesh file gives one object per part (material).
            let doc = spanned.into_inner();
            for object in object(loader, doc, &span, &mut materials, &mut read)? {
                object_spans.push(span.clone());
                objects.push(object);
            }
        }
        let camera = camera(loader, self.camera, &objects)?;
        let mut punctual = Vec::new();
        for spanned in self.lights {
            let span = Some(spanned.span());
            punctual.push(spanned.into_inner().light().map_err(|e| (span, e))?);
        }
        let scene = Scene {
            name: name.to_string(),
            camera,
            background,
            materials: materials.materials,
            material_names: materials.names,
            objects,
            punctual,
            defaults,
            inputs: Vec::new(),
        };
        // Media problems point at the object they are found at.
        super::media::check(&scene).map_err(|(i, e)| (object_spans[i].clone(), e))?;
        scene
            .validate()
            .map_err(|e: SceneError| (None, e.to_string()))?;
        Ok(scene)
    }

    fn from_scene(scene: &Scene) -> SceneDoc {
        let names = &scene.material_names;
        let materials = scene
            .materials
            .iter()
            .zip(names)
            .map(|(m, name)| {
                let doc = m.clone();
                (name.clone(), Spanned::new(0..0, doc))
            })
            .collect();
        let objects = scene
            .objects
            .iter()
            .map(|o| {
                let mut doc = ObjectDoc {
                    material: Some(names[o.material as usize].clone()),
                    rotate_y: (o.transform.rotate_y_degrees != 0.0)
                        .then_some(Num(o.transform.rotate_y_degrees)),
                    translate: (o.transform.translate != Vec3::ZERO)
                        .then(|| Spanned::new(0..0, V3::from(o.transform.translate))),
                    ..ObjectDoc::default()
                };
                match o.shape {
                    Shape::Surface(params) => doc.set_surface(params),
                    Shape::Cuboid { min, max } => {
                        doc.cuboid = Some(BoxDoc {
                            min: V3::from(min),
                            max: V3::from(max),
                        })
                    }
                    Shape::Mesh { ref mesh, scale } => {
                        doc.mesh = Some(MeshDoc {
                            file: mesh.source.clone(),
                            node: mesh.node.clone(),
                            part: Some(mesh.part),
                        });
                        doc.scale =
                            (scale != Vec3::ONE).then(|| ScaleDoc::PerAxis(V3::from(scale)));
                    }
                }
                Spanned::new(0..0, doc)
            })
            .collect();
        let c = &scene.camera;
        SceneDoc {
            render: Some(RenderDoc {
                width: Some(Spanned::new(0..0, scene.defaults.width)),
                height: Some(Spanned::new(0..0, scene.defaults.height)),
                max_depth: Some(Spanned::new(0..0, scene.defaults.max_depth)),
                background: Some(Spanned::new(
                    0..0,
                    match scene.background {
                        Background::Constant(c) => BackgroundDoc::Colour(Colour(V3::from(c))),
                        Background::Sky => BackgroundDoc::Named("sky".into()),
                        Background::Environment(ref e) => {
                            BackgroundDoc::Environment(EnvironmentDoc {
                                image: e.image.source.clone(),
                                strength: Some(Num(e.strength)),
                                rotate_y: (e.rotate_y_degrees != 0.0)
                                    .then_some(Num(e.rotate_y_degrees)),
                            })
                        }
                    },
                )),
            }),
            camera: Spanned::new(
                0..0,
                CameraDoc {
                    gltf: None,
                    look_from: Some(V3::from(c.look_from)),
                    look_at: Some(V3::from(c.look_at)),
                    up: Some(V3::from(c.up)),
                    vfov: Some(Num(c.vfov_degrees)),
                    aperture: (c.aperture != 0.0).then_some(Num(c.aperture)),
                    focus_distance: c.focus_distance.map(Num),
                },
            ),
            materials,
            objects,
            lights: scene
                .punctual
                .iter()
                .map(|l| Spanned::new(0..0, LightDoc::from_light(l)))
                .collect(),
        }
    }
}

/// The scene's materials as they are numbered: `[materials]` in name order, then the mesh
/// files' own as objects first use them.
struct SceneMaterials {
    index: BTreeMap<String, u32>,
    materials: Vec<Material>,
    names: Vec<String>,
}

impl SceneMaterials {
    /// `[materials]`, each validated.
    fn new(docs: BTreeMap<String, Spanned<Material>>) -> Result<Self, Located> {
        let mut out = SceneMaterials {
            index: BTreeMap::new(),
            materials: Vec::new(),
            names: Vec::new(),
        };
        for (name, doc) in docs {
            // Material tables are internally tagged, where serde cannot track spans of their
            // fields: errors point at the material.
            let span = Some(doc.span());
            let material = doc.into_inner();
            material
                .validate()
                .map_err(|message| (span, format!("material \"{}\": {message}", quoted(&name))))?;
            out.add(name, material);
        }
        Ok(out)
    }

    fn add(&mut self, name: String, material: Material) -> u32 {
        let i = self.materials.len() as u32;
        self.index.insert(name.clone(), i);
        self.materials.push(material);
        self.names.push(name);
        i
    }

    /// The material of an object's shape: the one it names, else its mesh part's own (added to
    /// the scene once, as "file#name").
    fn of_part(
        &mut self,
        named: Option<&str>,
        mesh: Option<&super::mesh::Mesh>,
        span: &Option<Range<usize>>,
    ) -> Result<u32, Located> {
        if let Some(name) = named {
            return lookup_material(&self.index, name).map_err(|e| (span.clone(), e));
        }
        let Some((mesh, own)) = mesh.and_then(|m| m.material.clone().map(|x| (m, x))) else {
            let what = match mesh {
                Some(m) => format!(
                    "mesh {} part \"{}\" has no material of its own{}",
                    m.source,
                    m.material_name,
                    m.library_refused
                        .as_ref()
                        .map_or(String::new(), |why| format!(" ({why})"))
                ),
                None => "an [[object]] needs a `material`".to_string(),
            };
            return Err((
                span.clone(),
                format!("{what}: name one with `material = \"...\"`"),
            ));
        };
        let name = format!("{}#{}", mesh.source, mesh.material_name);
        if let Some(&i) = self.index.get(&name) {
            return Ok(i);
        }
        own.validate().map_err(|e| {
            (
                span.clone(),
                format!(
                    "mesh {} material \"{}\": {e}",
                    mesh.source, mesh.material_name
                ),
            )
        })?;
        Ok(self.add(name, own))
    }
}

/// The objects one `[[object]]` places: one, or one per part of its mesh file.
fn object(
    loader: &Loader,
    o: ObjectDoc,
    span: &Option<Range<usize>>,
    materials: &mut SceneMaterials,
    read: &mut Vec<Arc<super::mesh::Mesh>>,
) -> Result<Vec<Object>, Located> {
    let parts = object_shapes(loader, &o, span, read)?;
    let mut placed = Vec::new();
    for (shape, mesh) in parts {
        shape.validate().map_err(|e| (span.clone(), e))?;
        let material = materials.of_part(o.material.as_deref(), mesh.as_deref(), span)?;
        placed.push((shape, material));
    }
    let transform = object_transform(&o)?;
    Ok(placed
        .into_iter()
        .map(|(shape, material)| Object {
            shape,
            material,
            transform,
        })
        .collect())
}

/// An `[[object]]`'s shape: its sphere, quad or box, or its mesh's parts (with the mesh, whose
/// own material it may take).
/// A shape an object places, and the mesh part it is (whose own material it may take).
type ShapePart = (Shape, Option<Arc<super::mesh::Mesh>>);

fn object_shapes(
    loader: &Loader,
    o: &ObjectDoc,
    span: &Option<Range<usize>>,
    read: &mut Vec<Arc<super::mesh::Mesh>>,
) -> Result<Vec<ShapePart>, Located> {
    let mut shapes = o.surfaces();
    if let Some(b) = &o.cuboid {
        shapes.push(Shape::Cuboid {
            min: b.min.vec(),
            max: b.max.vec(),
        });
    }
    let one_kind = shapes.len() + o.mesh.is_some() as usize;
    let mut parts: Vec<ShapePart> = shapes.into_iter().map(|s| (s, None)).collect();
    if let Some(m) = &o.mesh {
        let meshes = super::mesh::load(&loader.resolve(&m.file), &m.file, m.node.as_deref())
            .map_err(|e| (span.clone(), e))?;
        read.extend(meshes.iter().cloned());
        let meshes = match m.part {
            None => meshes,
            Some(p) => match meshes.get(p as usize) {
                Some(mesh) => vec![mesh.clone()],
                None => {
                    return Err((
                        span.clone(),
                        format!("mesh {} has {} parts, no part {p}", m.file, meshes.len()),
                    ));
                }
            },
        };
        let scale = o.scale.map_or(Vec3::ONE, ScaleDoc::vec);
        parts.extend(meshes.into_iter().map(|mesh| {
            (
                Shape::Mesh {
                    mesh: mesh.clone(),
                    scale,
                },
                Some(mesh),
            )
        }));
    } else if o.scale.is_some() {
        return Err((span.clone(), "`scale` applies to meshes only".into()));
    }
    if one_kind != 1 {
        return Err((
            span.clone(),
            format!(
                "an [[object]] needs exactly one of {}, `box` or `mesh`, found {one_kind}",
                crate::shape::KINDS
                    .iter()
                    .map(|k| format!("`{}`", k.name))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        ));
    }
    Ok(parts)
}

/// An `[[object]]`'s rotation about y and translation (within the scene's extent).
fn object_transform(o: &ObjectDoc) -> Result<Transform, Located> {
    let translate = match &o.translate {
        None => Vec3::ZERO,
        Some(t) => {
            let v = t.get_ref().vec();
            if v.abs().max_element() > super::MAX_EXTENT {
                return Err((
                    Some(t.span()),
                    format!(
                        "translate {v} reaches beyond {:e} from the origin: f32 geometry there is too coarse",
                        super::MAX_EXTENT
                    ),
                ));
            }
            v
        }
    };
    Ok(Transform {
        rotate_y_degrees: o.rotate_y.map(|r| r.0).unwrap_or(0.0),
        translate,
    })
}

/// `[render]`'s width, height and max depth, each in range, or its default.
fn render_defaults(render: Option<&RenderDoc>) -> Result<RenderDefaults, Located> {
    let setting = |field: Option<&Spanned<u32>>, what: &str, default: u32, max: u32| {
        let Some(field) = field else {
            return Ok(default);
        };
        let value = *field.get_ref();
        if value == 0 || value > max {
            return Err((
                Some(field.span()),
                format!("{what} must be in 1..={max}, got {value}"),
            ));
        }
        Ok(value)
    };
    Ok(RenderDefaults {
        width: setting(
            render.and_then(|r| r.width.as_ref()),
            "render.width",
            512,
            MAX_IMAGE_SIDE,
        )?,
        height: setting(
            render.and_then(|r| r.height.as_ref()),
            "render.height",
            512,
            MAX_IMAGE_SIDE,
        )?,
        max_depth: setting(
            render.and_then(|r| r.max_depth.as_ref()),
            "render.max_depth",
            10,
            MAX_DEPTH_LIMIT,
        )?,
    })
}

/// `[render] background`: a colour, the sky or an environment image (loaded here).
fn background(
    loader: &Loader,
    background_doc: Option<Spanned<BackgroundDoc>>,
) -> Result<Background, Located> {
    let background_span = background_doc.as_ref().map(|b| b.span());
    Ok(match background_doc.map(Spanned::into_inner) {
        None => Background::Constant(Vec3::ZERO),
        Some(BackgroundDoc::Colour(c)) => Background::Constant(c.0.vec()),
        Some(BackgroundDoc::Named(n)) if n == "sky" => Background::Sky,
        Some(BackgroundDoc::Environment(e)) => {
            let image = (loader.image(&e.image))
                .map_err(|m| (background_span.clone(), format!("background: {m}")))?;
            let env = crate::assets::environment::Environment::new(
                image,
                e.strength.map_or(1.0, |s| s.0),
                e.rotate_y.map_or(0.0, |r| r.0),
            )
            .map_err(|m| (background_span.clone(), m))?;
            Background::Environment(env)
        }
        Some(BackgroundDoc::Named(n)) => {
            return Err((
                background_span,
                format!(
                    "background must be a colour [r, g, b], \"sky\" or {{ image = \"file\", strength, rotate_y }}, got \"{}\"",
                    quoted(&n)
                ),
            ));
        }
    })
}

/// The camera named `name` of the first glTF file `objects` place that has one, placed with
/// the file: the first object that places the file scales, rotates and moves the camera as it
/// does the file's meshes.
fn file_camera(loader: &Loader, name: &str, objects: &[Object]) -> Result<Camera, String> {
    let mut files: Vec<(&str, Vec3, Transform)> = Vec::new();
    for object in objects {
        if let Shape::Mesh { mesh, scale } = &object.shape {
            let lower = mesh.source.to_ascii_lowercase();
            if (lower.ends_with(".glb") || lower.ends_with(".gltf"))
                && !files.iter().any(|(f, ..)| *f == mesh.source.as_str())
            {
                files.push((&mesh.source, *scale, object.transform));
            }
        }
    }
    if files.is_empty() {
        return Err(format!(
            "camera: gltf = \"{name}\" names a camera of a glTF file, and the scene places none"
        ));
    }
    let mut known: Vec<String> = Vec::new();
    for (source, scale, transform) in files {
        let path = loader.resolve(source);
        match super::gltf_scene::named_camera(&path, source, name)? {
            Ok(camera) => {
                let place = |p: Vec3| transform.apply_point(p * scale);
                return Ok(Camera {
                    look_from: place(camera.look_from),
                    look_at: place(camera.look_at),
                    up: transform.rotate_vector(camera.up * scale),
                    ..camera
                });
            }
            Err(names) => known.extend(names.into_iter().map(|n| format!("{source}: {n}"))),
        }
    }
    let known = if known.is_empty() {
        "they have no cameras".to_string()
    } else {
        let known: Vec<&str> = known.iter().map(String::as_str).collect();
        format!("cameras: {}", super::gltf_scene::listed(&known))
    };
    Err(format!(
        "camera: no glTF file the scene places has a camera named \"{}\" ({known})",
        quoted(name)
    ))
}

/// `[camera]`, validated: its own placement, or with `gltf = "NAME"` a camera of one of the
/// glTF files `objects` place (the first that has one of that name).
fn camera(
    loader: &Loader,
    camera: Spanned<CameraDoc>,
    objects: &[Object],
) -> Result<Camera, Located> {
    let camera_span = camera.span();
    let c = camera.into_inner();
    let at = |message: String| (Some(camera_span.clone()), message);
    let (look_from, look_at, up, vfov_degrees) = match (&c.gltf, c.look_from, c.look_at, c.vfov) {
        (Some(name), None, None, None) if c.up.is_none() => {
            let from_file = file_camera(loader, name, objects).map_err(at)?;
            (
                from_file.look_from,
                from_file.look_at,
                from_file.up,
                from_file.vfov_degrees,
            )
        }
        (Some(_), ..) => {
            return Err(at(
                "camera: `gltf` takes the camera's placement and field of view from the file; leave out look_from, look_at, up and vfov (aperture and focus_distance may stay)".into(),
            ));
        }
        (None, Some(from), Some(to), Some(vfov)) => (
            from.vec(),
            to.vec(),
            c.up.map(V3::vec).unwrap_or(Vec3::Y),
            vfov.0,
        ),
        (None, ..) => {
            return Err(at(
                "camera needs look_from, look_at and vfov, or gltf = \"NAME\" (a camera of a glTF file the scene places)".into(),
            ));
        }
    };
    let camera = Camera {
        look_from,
        look_at,
        up,
        vfov_degrees,
        aperture: c.aperture.map(|a| a.0).unwrap_or(0.0),
        focus_distance: c.focus_distance.map(|f| f.0),
    };
    camera
        .validate()
        .map_err(|e| (Some(camera_span.clone()), e.to_string()))?;
    Ok(camera)
}
