//! A glTF file's textures: TEXCOORD_0 arrives on triangles (v turned to rt-gpu's "up the
//! image") and is interpolated in hits; baseColorTexture x baseColorFactor becomes the base
//! colour, decoded from sRGB once, from a file beside the glTF file or a data URI; a bad
//! texture is a one-line error naming the file and what is wrong.

use crate::common;

use glam::{Vec2, Vec3};
use rt_gpu::assets::image::srgb_to_linear;
use rt_gpu::assets::texture::Texture;
use rt_gpu::scene::gltf_scene::load;
use rt_gpu::scene::{Material, Scene};
use std::path::{Path, PathBuf};

/// The 2x1 PNG written as `tex.png`: left texel red, right texel (sRGB) 128 grey.
fn write_png(dir: &Path) -> Vec<u8> {
    let image = image::RgbImage::from_raw(2, 1, vec![255, 0, 0, 128, 128, 128]).expect("2x1");
    let path = dir.join("tex.png");
    image.save(&path).expect("writes tex.png");
    std::fs::read(path).expect("reads tex.png")
}

/// `common::gltf::write_triangle` as `tri.gltf`, with `material` and `extra` top-level members
/// (textures, images, samplers).
fn write_gltf(dir: &Path, uvs: bool, material: &str, extra: &str) -> PathBuf {
    crate::common::gltf::write_triangle(dir, "tri.gltf", uvs, material, "", extra)
}

const TEXTURED: &str = r#"{ "name": "Painted", "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 }, "baseColorFactor": [0.5, 1, 1, 1], "metallicFactor": 0 } }"#;

fn images(uri: &str) -> String {
    format!(r#""textures": [{{ "source": 0 }}], "images": [{{ "uri": "{uri}" }}],"#)
}

fn base_colour(scene: &Scene) -> Texture {
    match &scene.materials[0] {
        Material::Pbr(pbr) => pbr.base_color.clone(),
        other => panic!("not pbr: {other:?}"),
    }
}

/// The CPU's hit of a ray straight down (-z) onto the triangle's centroid, (0, -1/3, 0).
fn hit_at_centroid(scene: &Scene) -> rt_gpu::shared::ray::Hit {
    let flat = rt_gpu::scene::flat::FlatScene::new(scene, 8, 8).expect("valid");
    let ray = rt_gpu::shared::ray::Ray {
        origin: Vec3::new(0.0, -1.0 / 3.0, 1.0) - flat.origin.as_vec3(),
        dir: -Vec3::Z,
    };
    rt_gpu::cpu::intersect::intersect(&flat, &ray).expect("hits")
}

#[test]
fn a_base_colour_texture_arrives_with_its_factor_and_uvs() {
    let dir = tempfile::tempdir().expect("temp dir");
    let png = write_png(dir.path());
    let data_uri = format!("data:image/png;base64,{}", base64::encode(&png));
    for uri in ["tex.png", data_uri.as_str()] {
        let path = write_gltf(dir.path(), true, TEXTURED, &images(uri));
        let (scene, _) = load(&path, "tri.gltf", None).expect("loads");
        let Texture::Image(image) = base_colour(&scene) else {
            panic!("not an image: {:?}", base_colour(&scene));
        };
        assert_eq!((image.width, image.height), (2, 1));
        // Decoded from sRGB, then times the factor (0.5, 1, 1), which a lookup applies.
        assert_eq!(image.factor, Vec3::new(0.5, 1.0, 1.0));
        assert_eq!(image.texel(0, 0) * image.factor, Vec3::new(0.5, 0.0, 0.0));
        let grey = srgb_to_linear(128.0 / 255.0);
        assert!(
            (image.texel(1, 0) * image.factor - Vec3::new(0.5 * grey, grey, grey))
                .abs()
                .max_element()
                < 1e-6
        );
        let rt_gpu::scene::Shape::Mesh { mesh, .. } = &scene.objects[0].shape else {
            panic!("a mesh");
        };
        let expected = [
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(0.5, 1.0),
        ];
        assert_eq!(mesh.uvs, vec![expected], "v turned up the image");
    }
}

/// A ray at the triangle's centroid hits it with the corners' mean texture coordinates; without
/// TEXCOORD_0 (and an untextured material) the hit's coordinates are its barycentric weights.
#[test]
fn hits_interpolate_the_corners_texture_coordinates() {
    let dir = tempfile::tempdir().expect("temp dir");
    write_png(dir.path());
    let path = write_gltf(dir.path(), true, TEXTURED, &images("tex.png"));
    let (scene, _) = load(&path, "tri.gltf", None).expect("loads");
    let flat = rt_gpu::scene::flat::FlatScene::new(&scene, 8, 8).expect("valid");
    assert_eq!(flat.triangle_uvs.len(), 1);
    let hit = hit_at_centroid(&scene);
    assert!(
        (hit.uv - Vec2::new(0.5, 1.0 / 3.0)).length() < 1e-5,
        "{}",
        hit.uv
    );

    let plain = r#"{ "name": "Plain", "pbrMetallicRoughness": { "metallicFactor": 0 } }"#;
    let path = write_gltf(dir.path(), true, plain, "");
    let (scene, _) = load(&path, "tri.gltf", None).expect("loads");
    let flat = rt_gpu::scene::flat::FlatScene::new(&scene, 8, 8).expect("valid");
    assert!(flat.triangle_uvs.is_empty(), "nothing reads them");
}

#[test]
fn bad_textures_are_one_line_errors_naming_the_file() {
    let dir = tempfile::tempdir().expect("temp dir");
    write_png(dir.path());
    std::fs::write(dir.path().join("junk.png"), b"not a png at all").expect("writes");
    let second_set = TEXTURED.replace(r#""index": 0 }"#, r#""index": 0, "texCoord": 1 }"#);
    let cases: [(bool, &str, String, &str); 6] = [
        (true, TEXTURED, images("missing.png"), "missing.png"),
        (true, TEXTURED, images("junk.png"), "image 0"),
        (
            true,
            TEXTURED,
            images("../tex.png"),
            "leaves the glTF file's folder",
        ),
        (
            true,
            TEXTURED,
            images("data:image/png;base64,@@@"),
            "not base64",
        ),
        (false, TEXTURED, images("tex.png"), "no TEXCOORD_0"),
        (true, &second_set, images("tex.png"), "no TEXCOORD_1"),
    ];
    for (uvs, material, extra, expected) in cases {
        let path = write_gltf(dir.path(), uvs, material, &extra);
        let err = load(&path, "tri.gltf", None).expect_err(expected);
        assert!(
            err.contains("tri.gltf") && err.contains(expected),
            "{expected}: {err}"
        );
        assert_eq!(err.lines().count(), 1, "{err}");
    }
    let out_of_range = TEXTURED.replace(r#""index": 0 }"#, r#""index": 3 }"#);
    let path = write_gltf(dir.path(), true, &out_of_range, &images("tex.png"));
    let err = load(&path, "tri.gltf", None).expect_err("texture 3 does not exist");
    assert!(
        err.contains("tri.gltf") && err.lines().count() == 1,
        "{err}"
    );
}

#[cfg(feature = "cli")]
#[test]
fn the_command_line_refuses_a_bad_texture_and_writes_nothing() {
    use common::cli::{rt_gpu, stderr};
    let dir = tempfile::tempdir().expect("temp dir");
    write_gltf(dir.path(), true, TEXTURED, &images("missing.png"));
    let out = rt_gpu(&["tri.gltf", "--spp", "1", "--backend", "cpu"], dir.path());
    let text = stderr(&out);
    assert!(!out.status.success());
    assert!(text.contains("missing.png"), "{text}");
    assert_eq!(text.trim_end().lines().count(), 1, "{text}");
    assert!(!dir.path().join("tri.png").exists());
}

/// The 1x1 PNG written as `normals.png`, of 8-bit values `texel` (191, 128, 238: the
/// tangent-space normal tilted 30 degrees toward +u).
fn write_normal_png(dir: &Path, texel: [u8; 3]) {
    let image = image::RgbImage::from_raw(1, 1, texel.to_vec()).expect("1x1");
    image
        .save(dir.join("normals.png"))
        .expect("writes normals.png");
}

fn normal_mapped(scale: &str) -> String {
    format!(
        r#"{{ "name": "Bumpy", "normalTexture": {{ "index": 0{scale} }}, "pbrMetallicRoughness": {{ "metallicFactor": 0 }} }}"#
    )
}

/// glTF's normalTexture arrives as a linear image with its `scale`, and bends the shading
/// normal of a hit in the triangle's tangent frame (MikkTSpace from its UVs: +u along +x on
/// this triangle, the geometric normal +z): toward +x by the map's tilt, x and y times scale.
#[test]
fn a_normal_texture_bends_the_shading_normal_by_its_scale() {
    let dir = tempfile::tempdir().expect("temp dir");
    write_normal_png(dir.path(), [191, 128, 238]);
    let texel = Vec3::new(191.0, 128.0, 238.0) / 255.0 * 2.0 - Vec3::ONE;
    for (scale, factor) in [("", 1.0), (r#", "scale": 0.5"#, 0.5)] {
        let path = write_gltf(
            dir.path(),
            true,
            &normal_mapped(scale),
            &images("normals.png"),
        );
        let (scene, _) = load(&path, "tri.gltf", None).expect("loads");
        let Material::Pbr(pbr) = &scene.materials[0] else {
            panic!("not pbr");
        };
        let map = pbr.normal_map.clone().expect("a normal map");
        assert_eq!(map.scale, factor);
        assert!((map.image.texel(0, 0) - (texel + Vec3::ONE) / 2.0).length() < 1e-6);
        let hit = hit_at_centroid(&scene);
        let expected = (texel * Vec3::new(factor, factor, 1.0)).normalize();
        assert!(
            (hit.shading - expected).length() < 1e-4,
            "scale {factor}: {} against {expected}",
            hit.shading
        );
        assert_eq!(hit.normal, Vec3::Z);
    }
    // A texel pointing below the surface (toward +u and down) is reflected into the upper
    // hemisphere, so it still slopes toward +u.
    write_normal_png(dir.path(), [255, 128, 0]);
    let path = write_gltf(dir.path(), true, &normal_mapped(""), &images("normals.png"));
    let (scene, _) = load(&path, "tri.gltf", None).expect("loads");
    let hit = hit_at_centroid(&scene);
    let expected = Vec3::new(1.0, 1.0 / 255.0, 1.0).normalize();
    assert!((hit.shading - expected).length() < 1e-4, "{}", hit.shading);
}

/// A normal map needs texture coordinates to lay it out: without TEXCOORD_0, on a second UV
/// set the file does not hold, or in a scene file on a sphere, it is a one-line error.
#[test]
fn a_normal_map_without_texture_coordinates_is_refused() {
    let dir = tempfile::tempdir().expect("temp dir");
    write_normal_png(dir.path(), [191, 128, 238]);
    for (uvs, scale, expected) in [
        (false, "", "no TEXCOORD_0"),
        (true, r#", "texCoord": 1"#, "no TEXCOORD_1"),
    ] {
        let path = write_gltf(
            dir.path(),
            uvs,
            &normal_mapped(scale),
            &images("normals.png"),
        );
        let err = load(&path, "tri.gltf", None).expect_err(expected);
        assert!(
            err.contains("tri.gltf") && err.contains(expected),
            "{expected}: {err}"
        );
        assert_eq!(err.lines().count(), 1, "{err}");
    }
    let png = dir.path().join("normals.png");
    let text = format!(
        "[camera]\nlook_from = [0, 0, 5]\nlook_at = [0, 0, 0]\nvfov = 40\n[materials]\nbumpy = {{ type = \"lambertian\", albedo = [0.5, 0.5, 0.5], normal_map = {{ image = \"{}\", scale = 2 }} }}\n[[object]]\nsphere = {{ center = [0, 0, 0], radius = 1 }}\nmaterial = \"bumpy\"\n",
        png.display()
    );
    let err = rt_gpu::scene::file::parse(&text, "bumpy.toml", "bumpy")
        .expect_err("a sphere has no texture coordinates")
        .to_string();
    assert!(
        err.contains("normal map") && err.contains("not a mesh"),
        "{err}"
    );
    assert_eq!(err.lines().count(), 1, "{err}");
    let too_steep = text.replace("scale = 2", "scale = 1e3");
    let err = rt_gpu::scene::file::parse(&too_steep, "bumpy.toml", "bumpy")
        .expect_err("scale beyond 100")
        .to_string();
    assert!(err.contains("scale"), "{err}");
}

/// An OBJ's map_Bump naming a grey image is a height map (tobj files `bump` there too), which
/// rt-gpu does not read as a normal map: a one-line error naming the file and the image.
#[test]
fn an_obj_height_map_is_not_taken_for_a_normal_map() {
    let dir = tempfile::tempdir().expect("temp dir");
    let grey = image::RgbImage::from_raw(2, 1, vec![10, 10, 10, 200, 200, 200]).expect("2x1");
    grey.save(dir.path().join("height.png")).expect("writes");
    std::fs::write(
        dir.path().join("m.mtl"),
        "newmtl Bumpy\nKd 0.8 0.8 0.8\nmap_Bump -bm 1.0 height.png\n",
    )
    .expect("writes");
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl Bumpy\nf 1/1 2/2 3/3\n";
    let path = dir.path().join("tri.obj");
    std::fs::write(&path, obj).expect("writes");
    let err = rt_gpu::scene::mesh::load(&path, "tri.obj", None).expect_err("a height map");
    assert!(
        err.contains("tri.obj") && err.contains("height.png") && err.contains("height (bump) map"),
        "{err}"
    );
    assert_eq!(err.lines().count(), 1, "{err}");
}

/// A file whose normals point against the winding (here -z on a triangle wound toward +z) is
/// shaded from the winding's side with its normals turned round; its normal map turns with
/// them: the bent normal is the file's own, glTF's x t + y b + z n in the frame of its normal
/// n = -z, its MikkTSpace tangent t = +x and b = w (n x t) = -y (MikkTSpace's sign w = +1
/// follows the UVs' winding, not the normals), turned round: toward -x, +y.
#[test]
fn a_normal_map_turns_with_normals_that_point_against_the_winding() {
    let dir = tempfile::tempdir().expect("temp dir");
    write_normal_png(dir.path(), [191, 128, 238]);
    let path = write_gltf(dir.path(), true, &normal_mapped(""), &images("normals.png"));
    let mut bin = std::fs::read(dir.path().join("tri.bin")).expect("reads");
    for _ in 0..3 {
        for x in [0.0f32, 0.0, -1.0] {
            bin.extend(x.to_le_bytes());
        }
    }
    std::fs::write(dir.path().join("tri.bin"), &bin).expect("writes");
    let json = std::fs::read_to_string(&path)
        .expect("reads")
        .replace(r#""byteLength": 60 }"#, r#""byteLength": 96 }"#)
        .replace(
            r#"{ "buffer": 0, "byteOffset": 36, "byteLength": 24 }]"#,
            r#"{ "buffer": 0, "byteOffset": 36, "byteLength": 24 }, { "buffer": 0, "byteOffset": 60, "byteLength": 36 }]"#,
        )
        .replace(
            r#""type": "VEC2" }"#,
            r#""type": "VEC2" }, { "bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC3" }"#,
        )
        .replace(r#""TEXCOORD_0": 1"#, r#""TEXCOORD_0": 1, "NORMAL": 2"#);
    std::fs::write(&path, json).expect("writes");
    let (scene, _) = load(&path, "tri.gltf", None).expect("loads");
    let hit = hit_at_centroid(&scene);
    let texel = Vec3::new(191.0, 128.0, 238.0) / 255.0 * 2.0 - Vec3::ONE;
    let expected = Vec3::new(-texel.x, texel.y, texel.z).normalize();
    assert!(
        (hit.shading - expected).length() < 1e-4,
        "{} against {expected}",
        hit.shading
    );
}

/// A texture's sampler arrives as its image's lookup (wrap modes per axis, magnification
/// filter); absent, the default (repeat, linear); one image read by two samplers is decoded
/// once and held with each.
#[test]
fn samplers_arrive_as_the_images_lookup() {
    use rt_gpu::assets::image_lookup::{Filter, ImageLookup, Wrap};
    let dir = tempfile::tempdir().expect("temp dir");
    write_png(dir.path());
    let with_sampler = |sampler: &str| {
        format!(
            r#""textures": [{{ "source": 0, "sampler": 0 }}], "samplers": [{sampler}], "images": [{{ "uri": "tex.png" }}],"#
        )
    };
    let cases = [
        (
            r#"{ "wrapS": 33071, "wrapT": 33648, "magFilter": 9728, "minFilter": 9728 }"#,
            ImageLookup {
                wrap_u: Wrap::Clamp,
                wrap_v: Wrap::Mirror,
                filter: Filter::Nearest,
                ..ImageLookup::default()
            },
        ),
        (
            r#"{ "wrapS": 33648, "magFilter": 9729 }"#,
            ImageLookup {
                wrap_u: Wrap::Mirror,
                wrap_v: Wrap::Repeat,
                filter: Filter::Linear,
                ..ImageLookup::default()
            },
        ),
        ("{}", ImageLookup::default()),
    ];
    for (sampler, expected) in cases {
        let path = write_gltf(dir.path(), true, TEXTURED, &with_sampler(sampler));
        let (scene, _) = load(&path, "tri.gltf", None).expect("loads");
        let Texture::Image(image) = base_colour(&scene) else {
            panic!("an image")
        };
        assert_eq!(image.lookup, expected, "{sampler}");
    }
}

/// KHR_texture_transform (offset, rotation, scale) maps the mesh's texture coordinates as the
/// extension's matrix T R S does, in glTF's coordinates (v down) before rt-gpu turns v up;
/// transforms that differ between a material's textures, or that name another UV set, are
/// one-line errors.
#[test]
fn texture_transforms_map_the_texture_coordinates() {
    let dir = tempfile::tempdir().expect("temp dir");
    write_png(dir.path());
    let transformed = |transform: &str| {
        format!(
            r#"{{ "name": "Painted", "pbrMetallicRoughness": {{ "baseColorTexture": {{ "index": 0, "extensions": {{ "KHR_texture_transform": {transform} }} }}, "metallicFactor": 0 }} }}"#
        )
    };
    let material =
        transformed(r#"{ "offset": [0.25, -0.5], "rotation": 1.5707963, "scale": [2, 3] }"#);
    let path = write_gltf(dir.path(), true, &material, &images("tex.png"));
    let (scene, _) = load(&path, "tri.gltf", None).expect("loads");
    let rt_gpu::scene::Shape::Mesh { mesh, .. } = &scene.objects[0].shape else {
        panic!("a mesh");
    };
    // glTF's corners (0, 1), (1, 1), (0.5, 0): scaled (0, 3), (2, 3), (1, 0); turned a quarter
    // (u' = v, v' = -u) (3, 0), (3, -2), (0, -1); offset (3.25, -0.5), (3.25, -2.5),
    // (0.25, -1.5); v turned up: 1 - v.
    let expected = [
        Vec2::new(3.25, 1.5),
        Vec2::new(3.25, 3.5),
        Vec2::new(0.25, 2.5),
    ];
    for (got, want) in mesh.uvs[0].iter().zip(expected) {
        assert!(
            (*got - want).length() < 1e-5,
            "{:?} against {expected:?}",
            mesh.uvs[0]
        );
    }

    let two = r#"{ "name": "Two", "pbrMetallicRoughness": { "baseColorTexture": { "index": 0, "extensions": { "KHR_texture_transform": { "scale": [2, 2] } } }, "metallicRoughnessTexture": { "index": 0 } } }"#;
    let other_set = transformed(r#"{ "texCoord": 1 }"#);
    // Issue 61: a scale of 1e38 or an offset of 3e38 rendered NaN; beyond what f32 resolves,
    // the coordinates are refused.
    let huge_scale = transformed(r#"{ "scale": [1e38, 1] }"#);
    let huge_offset = transformed(r#"{ "offset": [3e38, 0] }"#);
    for (material, expected) in [
        (two, "different KHR_texture_transforms"),
        (other_set.as_str(), "no TEXCOORD_1"),
        (huge_scale.as_str(), "texture coordinate"),
        (huge_offset.as_str(), "texture coordinate"),
    ] {
        let path = write_gltf(dir.path(), true, material, &images("tex.png"));
        let err = load(&path, "tri.gltf", None).expect_err(expected);
        assert!(
            err.contains("tri.gltf") && err.contains(expected),
            "{expected}: {err}"
        );
        assert_eq!(err.lines().count(), 1, "{err}");
    }
}

/// metallicRoughnessTexture arrives linear, and the material's metallic and roughness at a hit
/// are its factors times the texel's blue and green: the textured pbr evaluates there as the
/// plain pbr of those values does.
#[test]
fn a_metallic_roughness_texture_scales_the_factors_at_each_hit() {
    let dir = tempfile::tempdir().expect("temp dir");
    // Green 128 (roughness x 0.502), blue 64 (metallic x 0.251), read as linear values.
    let image = image::RgbImage::from_raw(1, 1, vec![0, 128, 64]).expect("1x1");
    image.save(dir.path().join("mr.png")).expect("writes");
    let material = r#"{ "name": "Worn", "pbrMetallicRoughness": { "baseColorFactor": [0.8, 0.6, 0.3, 1], "metallicFactor": 0.9, "roughnessFactor": 0.7, "metallicRoughnessTexture": { "index": 0 } } }"#;
    let path = write_gltf(dir.path(), true, material, &images("mr.png"));
    let (scene, _) = load(&path, "tri.gltf", None).expect("loads");
    let Material::Pbr(pbr) = &scene.materials[0] else {
        panic!("pbr")
    };
    let image = pbr
        .metallic_roughness()
        .cloned()
        .expect("a metallic-roughness image");
    assert_eq!(
        image.texel(0, 0),
        Vec3::new(0.0, 128.0 / 255.0, 64.0 / 255.0)
    );
    let hit = hit_at_centroid(&scene);
    let (metallic, roughness) = (0.9 * (64.0 / 255.0f32), 0.7 * (128.0 / 255.0f32));
    let plain = rt_gpu::material::Pbr::new(
        Texture::Colour(Vec3::new(0.8, 0.6, 0.3)),
        metallic,
        roughness,
        1.5,
        0.0,
    );
    let factors_only = rt_gpu::material::Pbr::new(
        Texture::Colour(Vec3::new(0.8, 0.6, 0.3)),
        0.9,
        0.7,
        1.5,
        0.0,
    );
    use rt_gpu::material::MaterialModel;
    let wo = Vec3::new(0.3, 0.1, 1.0).normalize();
    let mut differ_from_factors = 0;
    for wi in [
        Vec3::new(-0.3, -0.1, 1.0),
        Vec3::new(0.5, 0.2, 0.6),
        Vec3::new(0.0, 0.0, 1.0),
    ] {
        let wi = wi.normalize();
        let (textured, expected) = (pbr.eval(wo, wi, &hit), plain.eval(wo, wi, &hit));
        assert!(
            (textured - expected).abs().max_element() <= 1e-6 * expected.max_element(),
            "{textured} against {expected}"
        );
        assert!(
            (pbr.pdf(wo, wi, &hit) - plain.pdf(wo, wi, &hit)).abs()
                <= 1e-6 * plain.pdf(wo, wi, &hit)
        );
        differ_from_factors += (factors_only.eval(wo, wi, &hit) != textured) as usize;
    }
    assert_eq!(differ_from_factors, 3, "the texture changed nothing");
}

/// The 2x1 RGBA PNG written as `alpha.png`: white, the left texel opaque, the right one clear.
fn write_alpha_png(dir: &Path) {
    let image =
        image::RgbaImage::from_raw(2, 1, vec![255, 255, 255, 255, 255, 255, 255, 0]).expect("2x1");
    image.save(dir.join("alpha.png")).expect("writes alpha.png");
}

/// A ray straight down (-z) onto the triangle at (x, y); `None` if it passes.
fn hit_at(scene: &Scene, x: f32, y: f32) -> Option<rt_gpu::shared::ray::Hit> {
    let flat = rt_gpu::scene::flat::FlatScene::new(scene, 8, 8).expect("valid");
    let ray = rt_gpu::shared::ray::Ray {
        origin: Vec3::new(x, y, 1.0) - flat.origin.as_vec3(),
        dir: -Vec3::Z,
    };
    rt_gpu::cpu::intersect::intersect(&flat, &ray)
}

/// alphaMode MASK: rays pass where the base colour texture's alpha (times the factor's) is
/// below alphaCutoff and stop where it is not (u = (x + 1) / 2 across the triangle: texel 0 at
/// x = -0.5, texel 1 at x = 0.5); OPAQUE ignores alpha; BLEND stops a ray with probability
/// alpha (factor 0.3, no texture: 4 000 rays at distinct points, the fraction stopped within 5
/// standard deviations, 0.036, of 0.3).
#[test]
fn alpha_masks_cut_holes_and_blending_stops_rays_by_chance() {
    let dir = tempfile::tempdir().expect("temp dir");
    write_alpha_png(dir.path());
    let material = |mode: &str| {
        format!(
            r#"{{ "name": "Leaf", {mode} "pbrMetallicRoughness": {{ "baseColorTexture": {{ "index": 0 }}, "metallicFactor": 0 }} }}"#
        )
    };
    let cases = [
        (r#""alphaMode": "MASK","#, true, false),
        (r#""alphaMode": "MASK", "alphaCutoff": 0.3,"#, true, false),
        ("", true, true),
        (r#""alphaMode": "OPAQUE","#, true, true),
    ];
    for (mode, left, right) in cases {
        let path = write_gltf(dir.path(), true, &material(mode), &images("alpha.png"));
        let (scene, _) = load(&path, "tri.gltf", None).expect("loads");
        assert_eq!(
            hit_at(&scene, -0.5, -1.0 / 3.0).is_some(),
            left,
            "{mode} left"
        );
        assert_eq!(
            hit_at(&scene, 0.5, -1.0 / 3.0).is_some(),
            right,
            "{mode} right"
        );
    }
    // The mask's cutoff decides at a texel between: alpha 0.75 at u = 0.375 (x = -0.25).
    let at_cutoff = |cutoff: f32| {
        let mode = format!(r#""alphaMode": "MASK", "alphaCutoff": {cutoff},"#);
        let path = write_gltf(dir.path(), true, &material(&mode), &images("alpha.png"));
        let (scene, _) = load(&path, "tri.gltf", None).expect("loads");
        hit_at(&scene, -0.25, -1.0 / 3.0).is_some()
    };
    assert!(at_cutoff(0.7) && !at_cutoff(0.8));

    let blend = r#"{ "name": "Veil", "alphaMode": "BLEND", "pbrMetallicRoughness": { "baseColorFactor": [1, 1, 1, 0.3], "metallicFactor": 0 } }"#;
    let path = write_gltf(dir.path(), false, blend, "");
    let (scene, _) = load(&path, "tri.gltf", None).expect("loads");
    let mut rng = rt_gpu::shared::rng::Rng::for_sample(0, 0, 11);
    let n = 4000;
    let stopped = (0..n)
        .filter(|_| {
            let (x, y) = (0.6 * rng.next_f32() - 0.3, 0.6 * rng.next_f32() - 0.9);
            hit_at(&scene, x, y).is_some()
        })
        .count();
    let fraction = stopped as f64 / n as f64;
    eprintln!("BLEND at alpha 0.3 stopped {fraction}");
    assert!((fraction - 0.3).abs() < 0.036, "{fraction}");
}

/// A floor under an area light with two see-through triangles between: `mask.gltf`'s cut by
/// alpha.png's clear half (MASK), `veil.gltf`'s the same texture's alpha x 0.6 (BLEND); with
/// `twice`, the mask placed a second time, so that both placements are instances.
fn see_through_scene(dir: &Path, veil_alpha: f32, twice: bool) -> Scene {
    let mask = dir.join("mask");
    let veil = dir.join("veil");
    for (folder, material) in [
        (&mask, r#"{ "name": "Leaf", "alphaMode": "MASK", "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 }, "baseColorFactor": [0.9, 0.5, 0.2, 1], "metallicFactor": 0 } }"#.to_string()),
        (&veil, format!(r#"{{ "name": "Veil", "alphaMode": "BLEND", "pbrMetallicRoughness": {{ "baseColorTexture": {{ "index": 0 }}, "baseColorFactor": [0.2, 0.5, 0.9, {veil_alpha}], "metallicFactor": 0 }} }}"#)),
    ] {
        std::fs::create_dir_all(folder).expect("a folder");
        write_alpha_png(folder);
        write_gltf(folder, true, &material, &images("alpha.png"));
    }
    let text = r#"
[render]
background = [0, 0, 0]

[camera]
look_from = [0, -1.2, 1.6]
look_at = [0, 0, -0.5]
vfov = 70

[materials]
floor = { type = "lambertian", albedo = [0.7, 0.7, 0.7] }
lamp = { type = "light", radiance = [2, 2, 2] }

[[object]]
quad = { q = [-2, -2, -0.5], u = [4, 0, 0], v = [0, 4, 0] }
material = "floor"

[[object]]
quad = { q = [-1.5, -1.5, 2], u = [0, 3, 0], v = [3, 0, 0] }
material = "lamp"

[[object]]
mesh = { file = "mask/tri.gltf" }
translate = [-0.7, 0, 0]

[[object]]
mesh = { file = "veil/tri.gltf" }
translate = [0.7, 0, 0.3]
"#;
    let second =
        "\n[[object]]\nmesh = { file = \"mask/tri.gltf\" }\ntranslate = [0.2, -0.9, 0.2]\n";
    let path = dir.join("see-through.toml");
    std::fs::write(&path, format!("{text}{}", if twice { second } else { "" })).expect("writes");
    rt_gpu::scene::file::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// A shadow ray's search for any hit before a distance (`stopped_before`) sees the same holes
/// as the closest-hit search: over random rays through the see-through scene, its meshes placed
/// and instanced, "stopped" exactly when `intersect`'s hit lies before the distance (beyond
/// everything, at that hit, just past it, halfway to it); negative control: with every alpha
/// ignored, many rays are stopped before the see-through scene's closest hit (or where it has
/// none).
#[test]
fn a_shadow_ray_passes_see_through_surfaces_where_a_path_does() {
    use rt_gpu::cpu::intersect::{intersect, stopped_before};
    for twice in [false, true] {
        let dir = tempfile::tempdir().expect("temp dir");
        let scene = see_through_scene(dir.path(), 0.6, twice);
        let flat = rt_gpu::scene::flat::FlatScene::new(&scene, 8, 8).expect("valid");
        assert!(flat.see_through && flat.instances.is_empty() != twice);
        let mut opaque = flat.clone();
        for m in &mut opaque.materials {
            if let Material::Pbr(p) = m {
                *p = p.clone().with_alpha(None);
            }
        }
        opaque.see_through = false;
        let mut rng = rt_gpu::shared::rng::Rng::for_sample(0, 0, 17);
        let (mut stopped, mut differ_opaque) = (0, 0);
        for _ in 0..20_000 {
            let mut point = || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
            let origin = Vec3::new(3.0, 3.0, 1.0) * (point() - 0.5) + Vec3::new(0.0, 0.0, 0.8);
            let toward = Vec3::new(2.0, 2.0, 0.6) * (point() - 0.5);
            let ray = rt_gpu::shared::ray::Ray {
                origin: origin - flat.origin.as_vec3(),
                dir: (toward - origin).normalize(),
            };
            let closest = intersect(&flat, &ray).map_or(f32::INFINITY, |h| h.t);
            for before in [f32::INFINITY, closest, closest.next_up(), 0.5 * closest] {
                assert_eq!(
                    stopped_before(&flat, &ray, before),
                    closest < before,
                    "{ray:?}"
                );
            }
            stopped += closest.is_finite() as u32;
            // Where a hole lets the ray on to a farther hit, or out: ignoring alpha, something
            // stops it before.
            differ_opaque += stopped_before(&opaque, &ray, closest) as u32;
        }
        eprintln!("twice {twice}: {stopped} stopped, {differ_opaque} only where alpha is ignored");
        assert!(
            stopped > 5_000 && differ_opaque > 3_000,
            "{stopped}, {differ_opaque}"
        );
    }
}

/// See-through surfaces render the same estimator every way: naive against nee on the CPU (a
/// shadow ray and a path see the same holes), and the GPU against the CPU with nee (Welch z +
/// Sidak at family-wise 0.01, tests/it/common/stats.rs; 24x18 at 4 096 and 2 048 spp); negative
/// control: the veil's alpha 0.6 -> 0.63 (5%) on the GPU is told apart.
#[test]
fn see_through_surfaces_render_alike_every_way() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = see_through_scene(dir.path(), 0.6, false);
    let flat = rt_gpu::scene::flat::FlatScene::new(&scene, 8, 8).expect("valid");
    assert!(flat.see_through);
    common::renders_alike_every_way("see-through", &scene, || {
        see_through_scene(&dir.path().join("denser"), 0.63, false)
    });
}

/// The kernel's closest hits of rays straight down onto the see-through scene (its meshes
/// copied, and with the mask placed twice, instanced) equal the CPU's
/// (the same primitive, or both none) but for a few within rounding of a mask's edge or of a
/// veil's number; negative control: with every alpha ignored, the CPU's hits differ from the
/// kernel's for a large share of the rays.
#[cfg(feature = "gpu")]
#[test]
fn gpu_rays_pass_see_through_surfaces_where_cpu_rays_do() {
    use common::gpu::renderer;
    let Some(gpu) = renderer() else { return };
    for twice in [false, true] {
        let dir = tempfile::tempdir().expect("temp dir");
        let scene = see_through_scene(dir.path(), 0.6, twice);
        let flat = rt_gpu::scene::flat::FlatScene::new(&scene, 8, 8).expect("valid");
        assert_eq!(flat.instances.is_empty(), !twice);
        let mut opaque = flat.clone();
        for m in &mut opaque.materials {
            if let Material::Pbr(p) = m {
                *p = p.clone().with_alpha(None);
            }
        }
        opaque.see_through = false;
        let mut rng = rt_gpu::shared::rng::Rng::for_sample(0, 0, 13);
        let rays: Vec<(Vec3, Vec3)> = (0..20_000)
            .map(|_| {
                let p = Vec3::new(3.0 * rng.next_f32() - 1.5, 2.0 * rng.next_f32() - 1.0, 1.0);
                (p - flat.origin.as_vec3(), -Vec3::Z)
            })
            .collect();
        let gpu_hits = gpu.trace_rays(&flat, &rays).expect("rays run");
        let (mut differ, mut differ_opaque) = (0, 0);
        for ((origin, dir), g) in rays.iter().zip(&gpu_hits) {
            let ray = rt_gpu::shared::ray::Ray {
                origin: *origin,
                dir: *dir,
            };
            let primitive =
                |hit: Option<rt_gpu::shared::ray::Hit>| hit.map(|h| h.primitive.packed());
            let gpu_primitive = (g.hit == 1).then_some(g.primitive);
            differ += (primitive(rt_gpu::cpu::intersect::intersect(&flat, &ray)) != gpu_primitive)
                as usize;
            differ_opaque += (primitive(rt_gpu::cpu::intersect::intersect(&opaque, &ray))
                != gpu_primitive) as usize;
        }
        eprintln!(
            "{differ} of {} rays differ ({differ_opaque} from the opaque scene's)",
            rays.len()
        );
        assert!(differ <= rays.len() / 200, "{differ} rays differ");
        assert!(
            differ_opaque > rays.len() / 10,
            "alpha ignored went undetected"
        );
    }
}

/// Issue 61: one image that eight materials use with eight factors (and two samplers) is
/// decoded and held once, on the CPU and in the kernel's images (each factor and sampler made
/// its own copy: a 16384x8192 PNG used so took 10.9 GB and aborted); each material still reads
/// its factor x the image.
#[test]
fn an_image_used_with_many_factors_and_samplers_is_held_once() {
    let dir = tempfile::tempdir().expect("temp dir");
    write_png(dir.path());
    let materials: Vec<String> = (0..8)
        .map(|i| {
            let f = 0.2 + 0.1 * i as f32;
            format!(
                r#"{{ "name": "M{i}", "pbrMetallicRoughness": {{ "baseColorTexture": {{ "index": {} }}, "baseColorFactor": [{f}, 1, 1, 1], "metallicFactor": 0 }} }}"#,
                i % 2
            )
        })
        .collect();
    let extra = r#""samplers": [{ "magFilter": 9728 }], "textures": [{ "source": 0 }, { "source": 0, "sampler": 0 }], "images": [{ "uri": "tex.png" }],"#;
    let path = write_gltf(dir.path(), true, &materials.join(", "), extra);
    let text = std::fs::read_to_string(&path).expect("reads");
    let primitives: Vec<String> = (0..8)
        .map(|i| {
            format!(r#"{{ "attributes": {{ "POSITION": 0, "TEXCOORD_0": 1 }}, "material": {i} }}"#)
        })
        .collect();
    let text = text.replace(
        r#"[{ "attributes": { "POSITION": 0, "TEXCOORD_0": 1 }, "material": 0 }]"#,
        &format!("[{}]", primitives.join(", ")),
    );
    std::fs::write(&path, text).expect("writes");
    let (scene, _) = load(&path, "tri.gltf", None).expect("loads");
    let images: Vec<&rt_gpu::assets::image::Image> = (scene.materials.iter())
        .map(|m| match m {
            Material::Pbr(pbr) => match &pbr.base_color {
                Texture::Image(image) => &**image,
                other => panic!("not an image: {other:?}"),
            },
            other => panic!("not pbr: {other:?}"),
        })
        .collect();
    assert_eq!(images.len(), 8);
    for (i, image) in images.iter().enumerate() {
        assert!(
            std::sync::Arc::ptr_eq(&image.texels, &images[0].texels),
            "material {i}"
        );
        assert!((image.factor.x - (0.2 + 0.1 * i as f32)).abs() < 1e-6);
    }
    #[cfg(feature = "gpu")]
    {
        // The kernel's images take what they take with one of the materials alone.
        let bytes = |scene: &Scene| {
            let flat = rt_gpu::scene::flat::FlatScene::new(scene, 8, 8).expect("valid");
            rt_gpu::gpu::layout::ImageArray::plan(&flat).bytes()
        };
        let mut one = scene.clone();
        one.objects.iter_mut().for_each(|o| o.material = 0);
        assert_eq!(bytes(&scene), bytes(&one));
    }
}

/// A scene of a floor with `tri.gltf` above it, seen from above, under `background`.
fn floor_under_triangle(background: &str) -> String {
    format!(
        r#"[render]
background = {background}

[camera]
look_from = [0, -1.6, 2.2]
look_at = [0, 0, -0.5]
vfov = 60

[materials]
floor = {{ type = "lambertian", albedo = [0.7, 0.7, 0.7] }}

[[object]]
quad = {{ q = [-2, -2, -0.5], u = [4, 0, 0], v = [0, 4, 0] }}
material = "floor"

[[object]]
mesh = {{ file = "tri.gltf" }}
translate = [0, 0, 0.5]
"#
    )
}

/// A floor lit only by a two-sided emissive glTF triangle of `material` above it.
fn lit_by_emitter(dir: &Path, material: &str) -> Scene {
    std::fs::create_dir_all(dir).expect("a folder");
    write_gltf(dir, false, material, "");
    let text = floor_under_triangle("[0, 0, 0]");
    let path = dir.join("emitter.toml");
    std::fs::write(&path, text).expect("writes");
    rt_gpu::scene::file::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

fn emitter(mode: &str, alpha: f32) -> String {
    format!(
        r#"{{ "name": "Glow", "doubleSided": true, "emissiveFactor": [1, 1, 1], {mode} "pbrMetallicRoughness": {{ "baseColorFactor": [1, 1, 1, {alpha}] }} }}"#
    )
}

/// Issue 61: alpha cuts emitters as it cuts other surfaces (an emissive material with alpha 0
/// rendered as the opaque one). A floor lit only by a two-sided emissive triangle: masked out
/// (MASK, alpha 0), the triangle is a hole to camera, bounce and shadow rays, and the image is
/// black on both backends. Blended at alpha 0.5, the estimator agrees every way: naive against
/// nee on the CPU (a shadow ray toward the light passes where a path does), the GPU against the
/// CPU (Welch z + Sidak at family-wise 0.01, tests/it/common/stats.rs; 24x18 at 2 048 spp);
/// negative controls: alpha 0.55 on the GPU, and the opaque emitter, are told apart.
#[test]
fn alpha_cuts_emitters_for_every_ray() {
    use common::stats::compare;
    let dir = tempfile::tempdir().expect("temp dir");
    let masked = lit_by_emitter(
        &dir.path().join("masked"),
        &emitter(r#""alphaMode": "MASK","#, 0.0),
    );
    let brightest = |film: &rt_gpu::film::Film| {
        film.mean_rgb()
            .iter()
            .flatten()
            .fold(0.0f32, |m, &v| m.max(v))
    };
    let black = |film: &rt_gpu::film::Film| brightest(film) == 0.0;
    let opaque = lit_by_emitter(&dir.path().join("opaque"), &emitter("", 0.0));
    assert!(!black(&common::render_cpu(
        &opaque,
        &common::nee_opts(24, 18, 16, 5, 1)
    )));
    for integrator in [
        common::opts(24, 18, 64, 5, 1),
        common::nee_opts(24, 18, 64, 5, 1),
    ] {
        let film = common::render_cpu(&masked, &integrator);
        assert!(black(&film), "masked out: {}", brightest(&film));
    }
    let blended = lit_by_emitter(
        &dir.path().join("blended"),
        &emitter(r#""alphaMode": "BLEND","#, 0.5),
    );
    let nee = common::renders_alike_every_way("blended emitter", &blended, || {
        lit_by_emitter(
            &dir.path().join("denser"),
            &emitter(r#""alphaMode": "BLEND","#, 0.55),
        )
    });
    let verdict = compare(
        &nee,
        &common::render_cpu(&opaque, &common::nee_opts(24, 18, 2048, 5, 3)),
    );
    assert!(!verdict.passed(), "the opaque emitter went undetected");
    #[cfg(feature = "gpu")]
    {
        use common::gpu::{render_gpu, renderer};
        let Some(gpu) = renderer() else { return };
        let tuning = rt_gpu::gpu::Tuning::default();
        let film = render_gpu(&gpu, &masked, &common::nee_opts(24, 18, 64, 5, 1), &tuning);
        assert!(black(&film), "masked out on the gpu: {}", brightest(&film));
    }
}

/// A floor under a grey sky and an emissive, textured glTF triangle above it (two-sided),
/// whose emission is `emissive` x `tex.png` (red and grey texels) and whose own surface is
/// orange, dielectric and rough.
fn emissive_surface_scene(dir: &Path, emissive: [f32; 3]) -> Scene {
    std::fs::create_dir_all(dir).expect("a folder");
    write_png(dir);
    let [r, g, b] = emissive;
    let material = format!(
        r#"{{ "name": "Glow", "doubleSided": true, "emissiveFactor": [{r}, {g}, {b}], "emissiveTexture": {{ "index": 0 }}, "pbrMetallicRoughness": {{ "baseColorFactor": [0.9, 0.4, 0.1, 1], "metallicFactor": 0, "roughnessFactor": 0.5 }} }}"#
    );
    write_gltf(dir, true, &material, &images("tex.png"));
    let text = floor_under_triangle(r#"{ image = "sky.hdr" }"#);
    let mut sky = image::Rgb32FImage::new(8, 4);
    for p in sky.pixels_mut() {
        *p = image::Rgb([0.4, 0.45, 0.5]);
    }
    image::DynamicImage::ImageRgb32F(sky)
        .save(dir.join("sky.hdr"))
        .expect("writes sky.hdr");
    let path = dir.join("emissive.toml");
    std::fs::write(&path, text).expect("writes");
    rt_gpu::scene::file::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// Issue 62: an emissive glTF material keeps its surface (it was a light that reflected
/// nothing): at a hit it reflects its base colour and emits its factor x texture. Rendered,
/// the estimator agrees every way: naive against nee on the CPU (emitters that scatter, met by
/// BSDF sampling and by light sampling, MIS between them), the GPU against the CPU (Welch z +
/// Sidak at family-wise 0.01, tests/it/common/stats.rs; 24x18 at 2 048 spp); negative control:
/// its emission 5% brighter on the GPU is told apart.
#[test]
fn emissive_materials_keep_their_surface_on_both_backends() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = emissive_surface_scene(&dir.path().join("glow"), [0.8, 0.6, 0.4]);
    let flat = rt_gpu::scene::flat::FlatScene::new(&scene, 8, 8).expect("valid");
    let glow = flat
        .materials
        .iter()
        .find(|m| matches!(m, Material::Pbr(_)))
        .expect("the triangle's pbr");
    let ray = rt_gpu::shared::ray::Ray {
        origin: Vec3::new(-0.5, -0.5, 2.0) - flat.origin.as_vec3(),
        dir: -Vec3::Z,
    };
    let hit = rt_gpu::cpu::intersect::intersect(&flat, &ray).expect("hits the triangle");
    let reflected = glow.eval(Vec3::Z, Vec3::new(0.3, 0.0, 1.0).normalize(), &hit);
    assert!(
        reflected.x > 0.1 && reflected.x > reflected.z,
        "{reflected}"
    );
    // The left texel, red: 0.8 x (1, 0, 0).
    let emitted = glow.emitted(&hit);
    assert!(
        (emitted - Vec3::new(0.8, 0.0, 0.0)).length() < 1e-4,
        "{emitted}"
    );
    assert!(flat.lights.len() >= 2, "the triangle is an area light");

    common::renders_alike_every_way("emissive surface", &scene, || {
        emissive_surface_scene(&dir.path().join("brighter"), [0.84, 0.63, 0.42])
    });
}

/// Issue 62: KHR_materials_transmission's transmissionTexture scales the factor by its red
/// channel at each hit (it was ignored: TransmissionTest's opaque stripes were clear glass),
/// carried in the parameter image beside the metallic-roughness texture's channels: at a hit the
/// material is the plain one of factor x texel for all three (eval and pdf, reflected and
/// transmitted, within 1e-6), and the kernel renders it as the CPU does (Welch z + Sidak; lit
/// from one side), the texture's absence caught (z 179). A 2% larger factor (transmission 0.204
/// for 0.2) moves the image by less than its noise at 512 spp (z 2.5): the CPU check above is
/// the fine one.
#[test]
fn a_transmission_texture_scales_the_factor_at_each_hit() {
    let dir = tempfile::tempdir().expect("temp dir");
    // Transmission red 64 (x 0.251); metallic-roughness green 128, blue 32; both linear.
    image::RgbImage::from_raw(1, 1, vec![64, 200, 200])
        .expect("1x1")
        .save(dir.path().join("t.png"))
        .expect("writes");
    image::RgbImage::from_raw(1, 1, vec![0, 128, 32])
        .expect("1x1")
        .save(dir.path().join("mr.png"))
        .expect("writes");
    let material = |factor: f32| {
        format!(
            r#"{{ "pbrMetallicRoughness": {{ "baseColorFactor": [0.9, 0.8, 0.7, 1], "metallicFactor": 0.5, "roughnessFactor": 0.6, "metallicRoughnessTexture": {{ "index": 1 }} }}, "extensions": {{ "KHR_materials_transmission": {{ "transmissionFactor": {factor}, "transmissionTexture": {{ "index": 0 }} }} }} }}"#
        )
    };
    let extra = r#""extensionsUsed": ["KHR_materials_transmission"], "textures": [{ "source": 0 }, { "source": 1 }], "images": [{ "uri": "t.png" }, { "uri": "mr.png" }],"#;
    let path = write_gltf(dir.path(), true, &material(0.8), extra);
    let (scene, notes) = load(&path, "tri.gltf", None).expect("loads");
    assert!(
        !notes.iter().any(|n| n.contains("transmission")),
        "the texture is read: {notes:?}"
    );
    let Material::Pbr(pbr) = &scene.materials[0] else {
        panic!("pbr")
    };
    let hit = hit_at_centroid(&scene);
    let plain = rt_gpu::material::Pbr::new(
        Texture::Colour(Vec3::new(0.9, 0.8, 0.7)),
        0.5 * (32.0 / 255.0),
        0.6 * (128.0 / 255.0),
        1.5,
        0.8 * (64.0 / 255.0),
    );
    use rt_gpu::material::MaterialModel;
    let wo = Vec3::new(0.3, 0.1, 1.0).normalize();
    for wi in [
        Vec3::new(-0.3, -0.1, 1.0),
        Vec3::new(0.5, 0.2, 0.6),
        Vec3::new(-0.2, 0.1, -1.0),
    ] {
        let wi = wi.normalize();
        let (textured, expected) = (pbr.eval(wo, wi, &hit), plain.eval(wo, wi, &hit));
        assert!(
            (textured - expected).abs().max_element() <= 1e-6 * expected.max_element().max(1e-3),
            "{wi}: {textured} against {expected}"
        );
        let (p, q) = (pbr.pdf(wo, wi, &hit), plain.pdf(wo, wi, &hit));
        assert!(
            (p - q).abs() <= 1e-6 * q.max(1e-3),
            "{wi}: pdf {p} against {q}"
        );
    }

    #[cfg(feature = "gpu")]
    {
        use common::gpu::{render_gpu, renderer};
        use common::stats::compare;
        let Some(gpu) = renderer() else { return };
        // Lit from one side (a quarter of the environment white), so that what the glass
        // lets through differs from what the coat reflects.
        let quarter = rt_gpu::assets::image::Image::from_linear(
            "quarter",
            4,
            1,
            vec![4.0, 4.0, 4.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        )
        .expect("valid")
        .shared();
        let mut scene = scene.clone();
        scene.background = rt_gpu::scene::Background::Environment(
            rt_gpu::assets::environment::Environment::new(quarter, 1.0, 0.0).expect("valid"),
        );
        let opts = |seed| common::nee_opts(24, 24, 512, 6, seed);
        let cpu = common::render_cpu(&scene, &opts(1));
        let tuning = rt_gpu::gpu::Tuning::default();
        let verdict = compare(&cpu, &render_gpu(&gpu, &scene, &opts(2), &tuning));
        eprintln!("cpu vs gpu: {verdict:?}");
        assert!(verdict.passed(), "{verdict:?}");
        // Control: the kernel ignoring the texel's red (transmission 0.8 for 0.2).
        let mut ignored = scene.clone();
        if let Material::Pbr(p) = &mut ignored.materials[0] {
            p.transmission_in_red = false;
        }
        let verdict = compare(&cpu, &render_gpu(&gpu, &ignored, &opts(2), &tuning));
        eprintln!("gpu without the texture: {verdict:?}");
        assert!(!verdict.passed(), "the texture's absence went undetected");
    }
}

/// `tri.gltf` in `dir`: [`write_gltf`]'s triangle with TEXCOORD_0 `first` and, where given,
/// TEXCOORD_1 `second` (glTF's u, v per corner), of `material`, with `extra` members.
fn write_two_set_gltf(
    dir: &Path,
    material: &str,
    extra: &str,
    first: [[f32; 2]; 3],
    second: Option<[[f32; 2]; 3]>,
) -> PathBuf {
    std::fs::create_dir_all(dir).expect("a folder");
    let mut bin: Vec<u8> = Vec::new();
    for x in [-1.0f32, -1.0, 0.0, 1.0, -1.0, 0.0, 0.0, 1.0, 0.0] {
        bin.extend(x.to_le_bytes());
    }
    for x in first.iter().chain(second.iter().flatten()).flatten() {
        bin.extend(x.to_le_bytes());
    }
    std::fs::write(dir.join("tri.bin"), &bin).expect("writes");
    let (views, accessors, attribute) = match second {
        Some(_) => (
            r#", { "buffer": 0, "byteOffset": 60, "byteLength": 24 }"#,
            r#", { "bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC2" }"#,
            r#", "TEXCOORD_1": 2"#,
        ),
        None => ("", "", ""),
    };
    let json = format!(
        r#"{{
  "asset": {{ "version": "2.0" }},
  "buffers": [{{ "uri": "tri.bin", "byteLength": {} }}],
  "bufferViews": [{{ "buffer": 0, "byteOffset": 0, "byteLength": 36 }}, {{ "buffer": 0, "byteOffset": 36, "byteLength": 24 }}{views}],
  "accessors": [
    {{ "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [-1, -1, 0], "max": [1, 1, 0] }},
    {{ "bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2" }}{accessors}
  ],
  "materials": [{material}],
  {extra}
  "meshes": [{{ "primitives": [{{ "attributes": {{ "POSITION": 0, "TEXCOORD_0": 1{attribute} }}, "material": 0 }}] }}],
  "nodes": [{{ "name": "Triangle", "mesh": 0 }}],
  "scenes": [{{ "nodes": [0] }}],
  "scene": 0
}}"#,
        bin.len()
    );
    let path = dir.join("tri.gltf");
    std::fs::write(&path, json).expect("writes");
    path
}

/// Texture coordinates of the two-set triangle: `A` [`write_gltf`]'s, `B` those mirrored in
/// u and v (so tex.png's red and grey halves and a normal map's +u swap sides).
const UVS_A: [[f32; 2]; 3] = [[0.0, 1.0], [1.0, 1.0], [0.5, 0.0]];
const UVS_B: [[f32; 2]; 3] = [[1.0, 0.0], [0.0, 0.0], [0.5, 1.0]];

/// A material reading tex.png as base colour on UV set `base` and normals.png as normal map on
/// UV set `rest`, and where `emissive`, tex.png as emission (dimmed) on `rest` too: as
/// MultiUVTest reads its two images.
fn two_set_material(base: u32, rest: u32, emissive: bool) -> String {
    let emission = match emissive {
        true => format!(
            r#""emissiveFactor": [0.3, 0.3, 0.3], "emissiveTexture": {{ "index": 0, "texCoord": {rest} }}, "#
        ),
        false => String::new(),
    };
    format!(
        r#"{{ "name": "TwoSets", "doubleSided": true, {emission}"normalTexture": {{ "index": 1, "texCoord": {rest} }}, "pbrMetallicRoughness": {{ "baseColorTexture": {{ "index": 0, "texCoord": {base} }}, "metallicFactor": 0, "roughnessFactor": 0.5 }} }}"#
    )
}

/// The images [`two_set_material`] reads: tex.png and a normals.png tilted toward +u.
fn two_set_images(dir: &Path) -> &'static str {
    write_png(dir);
    write_normal_png(dir, [191, 128, 238]);
    r#""textures": [{ "source": 0 }, { "source": 1 }], "images": [{ "uri": "tex.png" }, { "uri": "normals.png" }],"#
}

/// [`two_placements_scene`] in `dir` of the two-set triangle of `material`, TEXCOORD_0
/// `first` and TEXCOORD_1 `second`.
fn two_set_scene(
    dir: &Path,
    material: &str,
    first: [[f32; 2]; 3],
    second: Option<[[f32; 2]; 3]>,
) -> Scene {
    std::fs::create_dir_all(dir).expect("a folder");
    let extra = two_set_images(dir);
    write_two_set_gltf(dir, material, extra, first, second);
    two_placements_scene(dir)
}

/// A grey-sky scene of a floor and `tri.gltf` placed twice (instanced unless it emits).
fn two_placements_scene(dir: &Path) -> Scene {
    let text = r#"[render]
background = [0.5, 0.5, 0.5]

[camera]
look_from = [0, -1.6, 2.6]
look_at = [0, 0, -0.5]
vfov = 60

[materials]
floor = { type = "lambertian", albedo = [0.7, 0.7, 0.7] }

[[object]]
quad = { q = [-3, -3, -0.5], u = [6, 0, 0], v = [0, 6, 0] }
material = "floor"

[[object]]
mesh = { file = "tri.gltf" }
translate = [-1.05, 0, 0.5]

[[object]]
mesh = { file = "tri.gltf" }
translate = [1.05, 0, 0.5]
"#;
    let path = dir.join("two.toml");
    std::fs::write(&path, text).expect("writes");
    rt_gpu::scene::file::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// Issue 62: a texture reading TEXCOORD_1 reads it (it was refused). The triangle whose every
/// texture (base colour, normal map, and emission where it has one) reads set 1 = B renders,
/// placed twice (instanced; copied where it emits), as the same triangle holding only set 0 = B
/// (films equal to 1e-6: the normal map's tangents follow set 1); reading set 0 = A instead is
/// told apart. A texCoord of 2 is refused in one line.
#[test]
fn a_second_uv_set_is_read_where_a_texture_names_it() {
    let dir = tempfile::tempdir().expect("temp dir");
    for emissive in [false, true] {
        let scene_of = |name: &str, base, rest, first, second| {
            let material = two_set_material(base, rest, emissive);
            let d = dir.path().join(format!("{name} {emissive}"));
            two_set_scene(&d, &material, first, second)
        };
        let second = scene_of("second", 1, 1, UVS_A, Some(UVS_B));
        let plain = scene_of("plain", 0, 0, UVS_B, None);
        let first = scene_of("first", 0, 0, UVS_A, Some(UVS_B));
        let flat = rt_gpu::scene::flat::FlatScene::new(&second, 8, 8).expect("valid");
        assert_eq!(flat.instances.is_empty(), emissive, "emitters are copied");
        assert_eq!(flat.triangle_uvs1.len(), flat.triangles.len());
        the_same_but_for_the_set(&second, &plain, &first);
    }

    // A third set is refused in one line naming it.
    let d = dir.path().join("third");
    std::fs::create_dir_all(&d).expect("a folder");
    let extra = two_set_images(&d);
    let material = two_set_material(2, 0, false);
    let path = write_two_set_gltf(&d, &material, extra, UVS_A, Some(UVS_B));
    let err = load(&path, "tri.gltf", None).expect_err("TEXCOORD_2");
    assert!(err.contains("TEXCOORD_2") && !err.contains('\n'), "{err}");
}

/// Asserts that `second` renders as `plain` (to 1e-6 of its light) and not as `first` (by 1%).
fn the_same_but_for_the_set(second: &Scene, plain: &Scene, first: &Scene) {
    let opts = common::nee_opts(24, 18, 64, 5, 3);
    let difference = common::relative_difference;
    let on_second = common::render_cpu(second, &opts);
    let same = difference(&on_second, &common::render_cpu(plain, &opts));
    let other = difference(&on_second, &common::render_cpu(first, &opts));
    eprintln!("set 1 = B vs set 0 = B: {same:.2e}; vs set 0 = A: {other:.2e}");
    assert!(
        same < 1e-6,
        "TEXCOORD_1 is not read as set 0 would be: {same}"
    );
    assert!(
        other > 1e-2,
        "reading TEXCOORD_0 instead went unseen: {other}"
    );
}

/// Issue 62: MultiUVTest's case, a base colour on TEXCOORD_0 and an emission and normal map on
/// TEXCOORD_1, renders the same estimator every way ([`common::renders_alike_every_way`]: naive vs
/// nee, CPU vs GPU, Welch z + Sidak); negative control: the emission and normal map read from
/// TEXCOORD_0 instead, on the GPU.
#[test]
fn two_uv_sets_render_alike_every_way() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mixed = two_set_scene(
        &dir.path().join("mixed"),
        &two_set_material(0, 1, true),
        UVS_A,
        Some(UVS_B),
    );
    common::renders_alike_every_way("two UV sets", &mixed, || {
        two_set_scene(
            &dir.path().join("first"),
            &two_set_material(0, 0, true),
            UVS_A,
            Some(UVS_B),
        )
    });
}
