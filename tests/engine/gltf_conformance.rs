//! glTF conformance, loader side: every model under ../shared/assets and assets/conformance loads (or is
//! refused with a message naming it); compressed and quantized meshes decode to the geometry of their
//! uncompressed originals within the quantization step; instancing, texture transforms, material
//! extensions and variants arrive in the data model with the spec's values; malformed compressed buffers
//! give messages, never panics; everything ignored is named once.

use crate::common::*;
use glam::{Vec2, Vec3};
use raykin::camera::CameraChoice;
use raykin::render::{Environment, RenderSettings};
use raykin::scene::{LoadOptions, SceneAsset, SceneError, load_gltf, load_gltf_slice};
use std::path::{Path, PathBuf};
use std::sync::Arc;

fn conformance() -> PathBuf {
    repo_root().join("assets/conformance")
}

fn load(path: impl AsRef<Path>) -> SceneAsset {
    let path = path.as_ref();
    load_gltf(path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"))
}

/// World-space positions of every drawn vertex in the rest pose.
fn world_positions(scene: &SceneAsset) -> Vec<Vec3> {
    let world = scene.rest_world_matrices();
    let mut drawn = vec![false; scene.nodes.len()];
    let mut stack = scene.roots.clone();
    while let Some(n) = stack.pop() {
        drawn[n] = true;
        stack.extend(&scene.nodes[n].children);
    }
    let mut out = Vec::new();
    for (i, node) in scene.nodes.iter().enumerate() {
        if let (true, Some(m)) = (drawn[i], node.mesh) {
            out.extend(
                scene.meshes[m]
                    .positions
                    .iter()
                    .map(|p| world[i].transform_point3(*p)),
            );
        }
    }
    out
}

/// Largest distance from a point of `a` to its nearest point of `b`, both ways (Hausdorff distance).
fn hausdorff(a: &[Vec3], b: &[Vec3]) -> f32 {
    let one_way = |a: &[Vec3], b: &[Vec3]| {
        a.iter()
            .map(|p| b.iter().map(|q| p.distance(*q)).fold(f32::MAX, f32::min))
            .fold(0.0f32, f32::max)
    };
    one_way(a, b).max(one_way(b, a))
}

fn extent(points: &[Vec3]) -> f32 {
    let (lo, hi) = points.iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    (hi - lo).max_element()
}

/// Total triangle area in world space, a check that connectivity decoded as well as positions.
fn world_area(scene: &SceneAsset) -> f32 {
    let world = scene.rest_world_matrices();
    let mut drawn = vec![false; scene.nodes.len()];
    let mut stack = scene.roots.clone();
    while let Some(n) = stack.pop() {
        drawn[n] = true;
        stack.extend(&scene.nodes[n].children);
    }
    let mut area = 0.0;
    for (i, node) in scene.nodes.iter().enumerate() {
        if let (true, Some(m)) = (drawn[i], node.mesh) {
            let mesh = &scene.meshes[m];
            for t in &mesh.triangles {
                let [a, b, c] = t.map(|v| world[i].transform_point3(mesh.positions[v as usize]));
                area += 0.5 * (b - a).cross(c - a).length();
            }
        }
    }
    area
}

/// Compressed `a` against uncompressed `b`: same triangle count, every vertex within `step` x the model's
/// extent of the other (the quantization step), same area within 1%.
fn assert_same_geometry(a: &SceneAsset, b: &SceneAsset, step: f32) {
    assert_eq!(
        a.triangle_count(),
        b.triangle_count(),
        "{} vs {}",
        a.source,
        b.source
    );
    let (pa, pb) = (world_positions(a), world_positions(b));
    let tolerance = step * extent(&pb);
    let d = hausdorff(&pa, &pb);
    assert!(
        d <= tolerance,
        "{} vs {}: vertices {d} apart, more than {tolerance}",
        a.source,
        b.source
    );
    let (area_a, area_b) = (world_area(a), world_area(b));
    assert!(
        (area_a - area_b).abs() <= 0.01 * area_b,
        "{}: area {area_a} vs {area_b}",
        a.source
    );
}

/// Every .gltf/.glb under the shared assets and assets/conformance either loads with triangles, or is refused
/// with a message that names it; warnings are never repeated.
#[test]
fn every_model_loads_or_is_refused_with_a_message() {
    let mut files = gltf_files_under(&shared_assets());
    files.extend(gltf_files_under(&conformance()));
    assert!(files.len() >= 70, "found only {} files", files.len());
    let mut refused = Vec::new();
    for path in &files {
        match load_gltf(path, &LoadOptions::default()) {
            Ok(scene) => {
                assert!(scene.triangle_count() > 0, "{}", path.display());
                let mut seen = std::collections::HashSet::new();
                for w in &scene.warnings {
                    assert!(!w.trim().is_empty(), "{}: empty warning", path.display());
                    assert!(seen.insert(w), "{}: warning twice: {w}", path.display());
                }
            }
            Err(e) => {
                let name = path.file_name().unwrap().to_string_lossy();
                assert!(e.to_string().contains(&*name), "{e} does not name {name}");
                refused.push(e.to_string());
            }
        }
    }
    // Nothing among these samples is beyond raykin now: each one loads.
    assert!(refused.is_empty(), "refused: {refused:#?}");
}

/// The new conformance files render: finite, non-negative, not black (16 x 16, 1 spp, sky light).
#[test]
fn conformance_files_render() {
    let (ctx, _gpu) = gpu();
    for path in gltf_files_under(&conformance()) {
        let scene = Arc::new(load(&path));
        let settings = RenderSettings {
            width: 16,
            height: 16,
            max_depth: 2,
            environment: Environment::Sky,
            ..Default::default()
        };
        let img = render(&ctx, &scene, settings, &CameraChoice::Auto, 1);
        let what = path.display().to_string();
        assert_all_finite(&img, &what);
        assert!(
            img.iter().flatten().all(|v| *v >= 0.0),
            "{what}: negative radiance"
        );
        assert!(
            mean_rgb(&img).iter().sum::<f64>() > 0.01,
            "{what}: black image"
        );
    }
}

#[test]
fn simple_instancing_draws_125_instances_of_one_mesh() {
    let dir = shared_assets().join("SimpleInstancing");
    let reference = load(dir.join("glTF/SimpleInstancing.gltf"));
    for scene in [
        load(dir.join("glTF-Binary/SimpleInstancing.glb")),
        reference.clone(),
    ] {
        let drawn: Vec<usize> = scene.nodes.iter().filter_map(|n| n.mesh).collect();
        assert_eq!(drawn.len(), 125, "{}", scene.source);
        assert!(
            drawn.iter().all(|&m| m == drawn[0]),
            "instances share one mesh"
        );
        assert_eq!(scene.meshes.len(), 1);
        // 125 distinct placements.
        let world = scene.rest_world_matrices();
        let mut centres: Vec<[i64; 3]> = scene
            .nodes
            .iter()
            .enumerate()
            .filter(|(_, n)| n.mesh.is_some())
            .map(|(i, _)| {
                world[i]
                    .w_axis
                    .truncate()
                    .to_array()
                    .map(|c| (c * 1e3) as i64)
            })
            .collect();
        centres.sort();
        centres.dedup();
        assert_eq!(centres.len(), 125);
    }
    // The same file through meshopt compression, quantized instance attributes and EXPONENTIAL/QUATERNION
    // filters: the same 125 cubes within 16-bit quantization.
    let packed = load(conformance().join("Meshopt/SimpleInstancing-meshopt.glb"));
    assert_eq!(
        packed.nodes.iter().filter(|n| n.mesh.is_some()).count(),
        125
    );
    assert_same_geometry(&packed, &reference, 2e-3);
}

#[test]
fn texture_transform_test_parses_to_the_spec_values() {
    let scene = load(shared_assets().join("TextureTransformTest/glTF/TextureTransformTest.gltf"));
    let transform = |name: &str| {
        let m = scene.materials.iter().find(|m| m.name == name).unwrap();
        m.base_color_texture.unwrap().transform
    };
    assert_eq!(transform("Offset U").offset, Vec2::new(0.5, 0.0));
    assert_eq!(transform("Offset V").offset, Vec2::new(0.0, 0.5));
    assert_eq!(transform("Offset UV").offset, Vec2::new(0.5, 0.5));
    assert!((transform("Rotation").rotation - std::f32::consts::FRAC_PI_8).abs() < 1e-6);
    assert_eq!(transform("Scale").scale, Vec2::splat(1.5));
    let all = transform("All");
    assert_eq!(
        (all.offset, all.rotation, all.scale),
        (Vec2::new(-0.2, -0.1), 0.3, Vec2::splat(1.5))
    );
    assert!(transform("Correct").is_identity());
    // The "Offset U" quad's UVs run over (0..0.5, 0..0.5): transformed they cover (0.5..1, 0..0.5), the
    // UV texture's other quadrant.
    let offset_u = transform("Offset U");
    assert_eq!(offset_u.apply(Vec2::new(0.0, 0.0)), Vec2::new(0.5, 0.0));
    assert_eq!(offset_u.apply(Vec2::new(0.5, 0.5)), Vec2::new(1.0, 0.5));
    // Rendered (texture_transform_moves_the_texels), so nothing is said about it.
    assert!(
        !scene
            .warnings
            .iter()
            .any(|w| w.starts_with("KHR_texture_transform")),
        "{:?}",
        scene.warnings
    );
}

#[test]
fn draco_meshes_match_their_uncompressed_versions() {
    let c = conformance();
    let s = shared_assets();
    for (draco, plain) in [
        (
            c.join("Box/glTF-Draco/Box.gltf"),
            s.join("Box/glTF/Box.gltf"),
        ),
        (
            c.join("MorphPrimitivesTest/glTF-Draco/MorphPrimitivesTest.gltf"),
            c.join("MorphPrimitivesTest/glTF/MorphPrimitivesTest.gltf"),
        ),
        (
            c.join("RiggedSimple/glTF-Draco/RiggedSimple.gltf"),
            s.join("RiggedSimple/glTF/RiggedSimple.gltf"),
        ),
    ] {
        let (a, b) = (load(&draco), load(&plain));
        // Draco quantizes positions to 11-14 bits over the bounding box.
        assert_same_geometry(&a, &b, 2.0f32.powi(-10));
        assert_eq!(
            a.meshes
                .iter()
                .map(|m| m.normals.is_some())
                .collect::<Vec<_>>(),
            b.meshes
                .iter()
                .map(|m| m.normals.is_some())
                .collect::<Vec<_>>()
        );
        assert!(a.warnings.is_empty(), "{}: {:?}", a.source, a.warnings);
    }
    // Skin data comes out of the bitstream too: the same joints and weights per position.
    let (a, b) = (
        load(c.join("RiggedSimple/glTF-Draco/RiggedSimple.gltf")),
        load(s.join("RiggedSimple/glTF/RiggedSimple.gltf")),
    );
    let (ma, mb) = (&a.meshes[0], &b.meshes[0]);
    let (wa, wb) = (
        ma.skin_weights.as_ref().unwrap(),
        mb.skin_weights.as_ref().unwrap(),
    );
    for (i, p) in ma.positions.iter().enumerate() {
        // The nearest uncompressed vertex (same position, up to quantization) has the same influences.
        let j = (0..mb.positions.len())
            .min_by(|&x, &y| {
                p.distance(mb.positions[x])
                    .total_cmp(&p.distance(mb.positions[y]))
            })
            .unwrap();
        assert_eq!(wa.joints[i], wb.joints[j], "vertex {i}");
        for k in 0..4 {
            assert!(
                (wa.weights[i][k] - wb.weights[j][k]).abs() < 1e-3,
                "vertex {i}"
            );
        }
    }
    // Morph targets of a Draco primitive stay uncompressed and in step with its vertices.
    let morph = load(c.join("MorphPrimitivesTest/glTF-Draco/MorphPrimitivesTest.gltf"));
    assert!(morph.meshes.iter().any(|m| !m.morph_targets.is_empty()));
}

#[test]
fn quantized_meshes_match_their_float_versions() {
    let (q, f) = (
        load(conformance().join("AnimatedMorphCube/glTF-Quantized/AnimatedMorphCube.gltf")),
        load(shared_assets().join("AnimatedMorphCube/glTF/AnimatedMorphCube.gltf")),
    );
    assert_same_geometry(&q, &f, 2.0f32.powi(-12));
    // Quantized morph targets (shorts, scaled by the node like the positions) move the vertices as far as
    // the float ones, in world space.
    let span = |s: &SceneAsset| -> Vec<f32> {
        let node = s.nodes.iter().position(|n| n.mesh == Some(0)).unwrap();
        let world = s.rest_world_matrices()[node];
        s.meshes[0]
            .morph_targets
            .iter()
            .map(|t| {
                t.positions
                    .iter()
                    .map(|d| world.transform_vector3(*d).length())
                    .fold(0.0, f32::max)
            })
            .collect()
    };
    let (sq, sf) = (span(&q), span(&f));
    assert_eq!(sq.len(), sf.len());
    for (a, b) in sq.iter().zip(&sf) {
        assert!((a - b).abs() <= 1e-3 * b.max(1.0), "{sq:?} vs {sf:?}");
    }
}

#[test]
fn meshopt_meshes_match_their_uncompressed_versions() {
    let c = conformance();
    let s = shared_assets();
    for (packed, plain) in [
        (
            "Meshopt/Box-meshopt-ext.glb",
            s.join("Box/glTF-Binary/Box.glb"),
        ),
        (
            "Meshopt/MorphPrimitivesTest-meshopt-khr.glb",
            c.join("MorphPrimitivesTest/glTF/MorphPrimitivesTest.gltf"),
        ),
    ] {
        let (a, b) = (load(c.join(packed)), load(&plain));
        // gltfpack's default: 14-bit positions.
        assert_same_geometry(&a, &b, 2.0f32.powi(-12));
    }
    // A skinned, animated file: every channel survives the QUATERNION filter as unit rotations.
    let rigged = load(c.join("Meshopt/RiggedSimple-meshopt.glb"));
    let plain = load(s.join("RiggedSimple/glTF-Binary/RiggedSimple.glb"));
    assert_eq!(rigged.triangle_count(), plain.triangle_count());
    assert_eq!(rigged.skins.len(), 1);
    assert!(!rigged.animations.is_empty() && !rigged.animations[0].channels.is_empty());
    for channel in &rigged.animations[0].channels {
        if let raykin::scene::ChannelValues::Rotation(r) = &channel.values {
            assert!(r.iter().all(|q| (q.length() - 1.0).abs() < 1e-2), "{r:?}");
        }
    }
}

#[test]
fn material_extensions_arrive_with_their_values_or_clamped_with_a_warning() {
    let scene = load(conformance().join("Authored/MaterialExtensions.gltf"));
    let good = &scene.materials[0].extensions;
    assert_eq!(good.ior, 1.7);
    assert_eq!(good.transmission.as_ref().unwrap().factor, 0.8);
    let volume = good.volume.as_ref().unwrap();
    assert_eq!(
        (
            volume.thickness,
            volume.attenuation_distance,
            volume.attenuation_color
        ),
        (0.25, 2.0, Vec3::new(0.9, 0.5, 0.2))
    );
    let specular = good.specular.as_ref().unwrap();
    assert_eq!(
        (specular.factor, specular.color),
        (0.7, Vec3::new(1.0, 0.9, 0.8))
    );
    let coat = good.clearcoat.as_ref().unwrap();
    assert_eq!((coat.factor, coat.roughness), (0.6, 0.2));
    let sheen = good.sheen.as_ref().unwrap();
    assert_eq!(
        (sheen.color, sheen.roughness),
        (Vec3::new(0.3, 0.2, 0.1), 0.5)
    );
    let film = good.iridescence.as_ref().unwrap();
    assert_eq!(
        (
            film.factor,
            film.ior,
            film.thickness_min,
            film.thickness_max
        ),
        (1.0, 1.8, 200.0, 600.0)
    );
    let aniso = good.anisotropy.as_ref().unwrap();
    assert_eq!((aniso.strength, aniso.rotation), (0.5, 0.75));
    assert_eq!(good.dispersion, 0.33);
    let dt = good.diffuse_transmission.as_ref().unwrap();
    assert_eq!((dt.factor, dt.color), (0.4, Vec3::new(0.2, 0.9, 0.3)));
    assert_eq!(scene.materials[0].emissive_strength, 4.0);

    // Out-of-range values: clamped into the schema's range (or the default), each with a warning.
    let bad = &scene.materials[1].extensions;
    assert_eq!(bad.ior, 1.0);
    assert_eq!(bad.transmission.as_ref().unwrap().factor, 1.0);
    let volume = bad.volume.as_ref().unwrap();
    assert!(volume.thickness.is_finite() && volume.thickness > 0.0);
    assert_eq!(volume.attenuation_distance, f32::INFINITY);
    assert_eq!(volume.attenuation_color, Vec3::new(1.0, 0.0, 0.5));
    let coat = bad.clearcoat.as_ref().unwrap();
    assert_eq!((coat.factor, coat.roughness), (0.0, 0.0));
    let sheen = bad.sheen.as_ref().unwrap();
    assert_eq!((sheen.color, sheen.roughness), (Vec3::ZERO, 1.0));
    assert_eq!(bad.iridescence.as_ref().unwrap().ior, 1.0);
    assert_eq!(bad.anisotropy.as_ref().unwrap().strength, 1.0);
    assert_eq!(bad.dispersion, 0.0);
    assert_eq!(bad.diffuse_transmission.as_ref().unwrap().factor, 1.0);
    for what in [
        "KHR_materials_ior ior 0.5",
        "transmissionFactor 3",
        "thicknessFactor",
        "attenuationDistance 0",
        "attenuationColor 2",
        "attenuationColor -1",
        "clearcoatFactor -0.5",
        "clearcoatRoughnessFactor is not a number",
        "sheenColorFactor is not three numbers",
        "sheenRoughnessFactor 2",
        "iridescenceIor -1",
        "anisotropyStrength 7",
        "dispersion -2",
        "diffuseTransmissionFactor 1.5",
    ] {
        let hits = scene
            .warnings
            .iter()
            .filter(|w| w.contains("`out of range`") && w.contains(what))
            .count();
        assert_eq!(
            hits, 1,
            "`{what}` warned {hits} times: {:#?}",
            scene.warnings
        );
    }
    // IOR 0 is the schema's special value (Fresnel f0 = 1), kept as is.
    assert_eq!(scene.materials[2].extensions.ior, 0.0);
    // Parsed but not rendered yet: one line per extension, naming the materials; none for those rendered.
    for ext in raykin::scene::material_extensions::RENDERED {
        assert!(
            !scene.warnings.iter().any(|w| w.starts_with(ext)),
            "{ext} is rendered: {:#?}",
            scene.warnings
        );
    }
    for ext in [
        "KHR_materials_iridescence",
        "KHR_materials_anisotropy",
        "KHR_materials_dispersion",
        "KHR_materials_diffuse_transmission",
    ] {
        let lines: Vec<&String> = scene
            .warnings
            .iter()
            .filter(|w| w.starts_with(ext) && w.contains("not rendered yet"))
            .collect();
        assert_eq!(lines.len(), 1, "{ext}: {:#?}", scene.warnings);
        assert!(lines[0].contains("`layered`"), "{}", lines[0]);
    }
}

#[test]
fn sample_material_extensions_are_parsed() {
    let c = conformance();
    let coat = load(c.join("ClearCoatCarPaint/glTF-Binary/ClearCoatCarPaint.glb"));
    let paint = &coat.materials[0];
    assert_eq!(
        paint
            .extensions
            .clearcoat
            .as_ref()
            .map(|c| (c.factor, c.roughness)),
        Some((1.0, 0.0))
    );
    // Its normal map repeats three times (a transform on the normalTexture slot).
    assert_eq!(
        paint.normal_texture.unwrap().transform.scale,
        Vec2::splat(3.0)
    );
    let unlit = load(c.join("UnlitTest/glTF-Binary/UnlitTest.glb"));
    assert!(unlit.materials.iter().all(|m| m.extensions.unlit));
    let spec = load(c.join("SpecularTest/glTF-Binary/SpecularTest.glb"));
    assert!(
        spec.materials
            .iter()
            .filter(|m| m.extensions.specular.is_some())
            .count()
            > 5
    );
    let aniso = load(c.join("AnisotropyStrengthTest/glTF-Binary/AnisotropyStrengthTest.glb"));
    assert!(
        aniso
            .materials
            .iter()
            .any(|m| m.extensions.anisotropy.is_some())
    );
    let ttmt = load(c.join("TextureTransformMultiTest/glTF-Binary/TextureTransformMultiTest.glb"));
    // Transforms on normal, emissive and clear-coat slots, not only base colour.
    let transformed =
        |pick: &dyn Fn(&raykin::scene::Material) -> Option<raykin::scene::TextureRef>| {
            ttmt.materials
                .iter()
                .filter_map(pick)
                .any(|t| !t.transform.is_identity())
        };
    assert!(transformed(&|m| m.base_color_texture));
    assert!(transformed(&|m| m.normal_texture));
    assert!(transformed(&|m| m
        .extensions
        .clearcoat
        .as_ref()
        .and_then(|c| c.texture)));
    let glass = load(shared_assets().join("AttenuationTest/glTF-Binary/AttenuationTest.glb"));
    assert!(glass.materials.iter().any(|m| {
        m.extensions
            .volume
            .as_ref()
            .is_some_and(|v| v.attenuation_distance.is_finite())
    }));
}

#[test]
fn variants_select_materials_by_name() {
    let path = conformance().join("Authored/MaterialVariants.gltf");
    let mut scene = load(&path);
    assert_eq!(scene.variants, ["red", "blue"]);
    let materials = |s: &SceneAsset| s.meshes[0].triangle_materials.clone();
    assert_eq!(materials(&scene), [0, 0]);
    scene.select_variant(Some("red")).unwrap();
    assert_eq!(
        (materials(&scene), scene.meshes[0].primitives[0].material),
        (vec![1, 1], 1)
    );
    scene.select_variant(Some("blue")).unwrap();
    assert_eq!(materials(&scene), [2, 2]);
    scene.select_variant(None).unwrap();
    assert_eq!(materials(&scene), [0, 0]);
    let err = scene.select_variant(Some("green")).unwrap_err().to_string();
    assert!(
        err.contains("MaterialVariants.gltf")
            && err.contains("`green`")
            && err.contains("`red`, `blue`"),
        "{err}"
    );
    // The error a CLI reports for an unknown name is a SceneError naming the file.
    assert!(matches!(
        scene.select_variant(Some("green")),
        Err(SceneError::UnknownVariant { .. })
    ));
    assert_eq!(scene.active_variant, None);
    // The loader picks one by name (`--variant`), or refuses an unknown name naming the file.
    let options = |v: &str| raykin::scene::LoadOptions {
        variant: Some(v.into()),
        ..Default::default()
    };
    let blue = raykin::scene::load_gltf(&path, &options("blue")).unwrap();
    assert_eq!(materials(&blue), [2, 2]);
    let err = raykin::scene::load_gltf(&path, &options("green")).unwrap_err();
    assert!(matches!(err, SceneError::UnknownVariant { .. }), "{err}");
}

#[test]
fn ktx2_only_textures_fall_back_to_the_factor_with_a_warning() {
    let scene = load(conformance().join("Authored/Ktx2OnlyTexture.gltf"));
    assert!(scene.materials[0].base_color_texture.is_none());
    let lines: Vec<&String> = scene
        .warnings
        .iter()
        .filter(|w| w.contains("KTX2"))
        .collect();
    assert!(!lines.is_empty(), "{:?}", scene.warnings);
    assert!(lines.iter().all(|w| w.contains("image 0")), "{lines:?}");
}

#[test]
fn every_ignored_piece_is_named_once() {
    let scene = load(conformance().join("Authored/IgnoredPieces.gltf"));
    for what in [
        "`EXT_raykin_unknown` is not supported",
        "occlusion textures ignored",
        "mode Points",
        "image 1 (image/png in bufferView 5) skipped",
    ] {
        let n = scene.warnings.iter().filter(|w| w.contains(what)).count();
        assert_eq!(n, 1, "`{what}`: {:#?}", scene.warnings);
    }
    // KHR_lights_punctual, listed in the file, is read (issue 15), so it is not among the ignored pieces.
    assert!(
        !scene
            .warnings
            .iter()
            .any(|w| w.contains("KHR_lights_punctual")),
        "{:#?}",
        scene.warnings
    );
    // The decodable image without a URI is used.
    assert!(scene.materials[0].base_color_texture.is_none());
    assert_eq!(scene.images[0].width, 1);
}

/// A deterministic xorshift stream for the mutation loops.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Mutates `bytes[range]`: flips bits, overwrites bytes with extremes, or truncates-by-zeroing a tail.
fn mutate(bytes: &mut [u8], range: std::ops::Range<usize>, rng: &mut Rng) {
    let len = range.len();
    match rng.below(3) {
        0 => {
            for _ in 0..1 + rng.below(4) {
                let i = range.start + rng.below(len);
                bytes[i] ^= 1 << rng.below(8);
            }
        }
        1 => {
            let i = range.start + rng.below(len);
            bytes[i] = [0, 0xff, 0x7f, 0x80][rng.below(4)];
        }
        _ => {
            let from = range.start + rng.below(len);
            bytes[from..range.end].fill(0);
        }
    }
}

/// Counts panics anywhere in the process while `f` runs (the loader catches them, so count at the hook).
fn panics_during(f: impl FnOnce()) -> Vec<String> {
    use std::sync::Mutex;
    static SEEN: Mutex<Vec<String>> = Mutex::new(Vec::new());
    let previous = std::panic::take_hook();
    std::panic::set_hook(Box::new(|info| {
        SEEN.lock()
            .unwrap()
            .push(info.location().map_or("?".into(), |l| l.to_string()));
    }));
    f();
    std::panic::set_hook(previous);
    std::mem::take(&mut *SEEN.lock().unwrap())
}

/// A loaded scene or a refusal from a mutated file must be sane: messages name the file, and for Draco or
/// meshopt failures the skipped primitive or bufferView; positions stay finite.
fn check_outcome(result: Result<SceneAsset, SceneError>, name: &str) {
    match result {
        Ok(scene) => {
            for m in &scene.meshes {
                assert!(m.positions.iter().all(|p| p.is_finite()), "{name}");
                assert!(
                    m.triangles
                        .iter()
                        .flatten()
                        .all(|&i| (i as usize) < m.positions.len())
                );
            }
            for w in &scene.warnings {
                if w.contains("Draco") || w.contains("draco") {
                    assert!(w.contains("primitive"), "{w}");
                }
            }
        }
        Err(e) => assert!(e.to_string().contains(name), "{e}"),
    }
}

#[test]
fn malformed_draco_buffers_give_messages_never_panics() {
    let c = conformance();
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let mut runs = 0;
    let panics = panics_during(|| {
        for file in [
            "Box/glTF-Draco/Box.gltf",
            "MorphPrimitivesTest/glTF-Draco/MorphPrimitivesTest.gltf",
            "RiggedSimple/glTF-Draco/RiggedSimple.gltf",
        ] {
            let path = c.join(file);
            let mut json: serde_json::Value =
                serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
            let uri = json["buffers"][0]["uri"].as_str().unwrap().to_string();
            let bin = std::fs::read(path.parent().unwrap().join(uri)).unwrap();
            // Mutate only the Draco bitstreams (the bufferViews the primitives' extensions name).
            let views: Vec<std::ops::Range<usize>> = json["meshes"]
                .as_array()
                .unwrap()
                .iter()
                .flat_map(|m| m["primitives"].as_array().unwrap().clone())
                .filter_map(|p| {
                    p["extensions"]["KHR_draco_mesh_compression"]["bufferView"].as_u64()
                })
                .map(|v| {
                    let view = &json["bufferViews"][v as usize];
                    let offset = view["byteOffset"].as_u64().unwrap_or(0) as usize;
                    offset..offset + view["byteLength"].as_u64().unwrap() as usize
                })
                .collect();
            for _ in 0..120 {
                let mut bytes = bin.clone();
                let range = views[rng.below(views.len())].clone();
                mutate(&mut bytes, range, &mut rng);
                json["buffers"][0]["uri"] = serde_json::Value::String(format!(
                    "data:application/octet-stream;base64,{}",
                    base64_encode(&bytes)
                ));
                let doc = serde_json::to_vec(&json).unwrap();
                let name = format!("mutated-{}", path.file_name().unwrap().to_string_lossy());
                let result = load_gltf_slice(
                    &doc,
                    path.parent().unwrap(),
                    Path::new(&name),
                    &LoadOptions::default(),
                );
                check_outcome(result, &name);
                runs += 1;
            }
        }
    });
    assert_eq!(runs, 360);
    // Panics inside the Draco decoder (draco-oxide asserts on some malformed streams) are caught where it is
    // called and become the primitive's warning; none may come from raykin's own code.
    assert!(
        panics
            .iter()
            .all(|p| !p.contains("engine/src") && !p.contains("tests/")),
        "panics in raykin: {panics:?}"
    );
    eprintln!(
        "{runs} mutated Draco files, {} decoder panics caught",
        panics.len()
    );
}

#[test]
fn malformed_meshopt_buffers_give_messages_never_panics() {
    let c = conformance();
    let mut rng = Rng(0x2545_f491_4f6c_dd1d);
    let mut runs = 0;
    let panics = panics_during(|| {
        for file in [
            "Meshopt/Box-meshopt-ext.glb",
            "Meshopt/MorphPrimitivesTest-meshopt-khr.glb",
            "Meshopt/RiggedSimple-meshopt.glb",
            "Meshopt/SimpleInstancing-meshopt.glb",
        ] {
            let glb = std::fs::read(c.join(file)).unwrap();
            // The BIN chunk follows the 12-byte header and the JSON chunk.
            let json_len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
            let bin_start = 20 + json_len + 8;
            for _ in 0..100 {
                let mut bytes = glb.clone();
                mutate(&mut bytes, bin_start..glb.len(), &mut rng);
                let name = format!(
                    "mutated-{}",
                    Path::new(file).file_name().unwrap().to_string_lossy()
                );
                let result = load_gltf_slice(&bytes, &c, Path::new(&name), &LoadOptions::default());
                check_outcome(result, &name);
                runs += 1;
            }
        }
    });
    assert_eq!(runs, 400);
    assert!(panics.is_empty(), "panics: {panics:?}");
}

fn base64_encode(bytes: &[u8]) -> String {
    use base64::Engine as _;
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

/// KHR_texture_transform in the renderer: a quad filling the view, emitting a 2x2-texel texture (red, green,
/// blue, white; nearest, repeat) through offset, rotation and scale, seen at depth 0 so each pixel is exactly
/// the texel its UV lands in. The expected texel per pixel comes from the specification's formula written here
/// (`uv' = T R S uv`, rotation rows `(cos, sin)`, `(-sin, cos)`), not from raykin's code; only pixels whose whole
/// footprint maps to one texel are compared. The identity transform checks the pixel-to-UV mapping itself.
#[test]
fn texture_transform_moves_the_texels() {
    use raykin::scene::{Image, Material, MeshData, Texture, TextureRef, TextureTransform, Wrap};
    const SIZE: u32 = 32;
    let colours = [
        [1.0f32, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 1.0, 1.0],
    ];
    let rgba8: Vec<u8> = colours
        .iter()
        .flat_map(|c| {
            [
                (c[0] * 255.0) as u8,
                (c[1] * 255.0) as u8,
                (c[2] * 255.0) as u8,
                255,
            ]
        })
        .collect();
    // The quad spans [-1, 1]^2 at z = 0 with u along +x and v down the image (glTF's convention).
    let quad = MeshData {
        uv0: Some(vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(0.0, 1.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(1.0, 0.0),
        ]),
        ..quad_mesh(
            [
                Vec3::new(-1.0, 1.0, 0.0),
                Vec3::new(-1.0, -1.0, 0.0),
                Vec3::new(1.0, -1.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
            ],
            0,
        )
    };
    let render_with = |ctx: &raykin::gpu::GpuContext, transform: TextureTransform| {
        let mut scene = raykin::scene::procedural::scene_from_meshes(
            "texture transform",
            vec![(quad.clone(), Default::default())],
            vec![Material {
                name: "emitter".into(),
                base_color: glam::Vec4::new(0.0, 0.0, 0.0, 1.0),
                emissive: Vec3::ONE,
                emissive_texture: Some(TextureRef {
                    texture: 0,
                    tex_coord: 0,
                    transform,
                }),
                double_sided: true,
                ..Default::default()
            }],
        );
        scene.images = vec![Image {
            name: "2x2".into(),
            width: 2,
            height: 2,
            rgba8: rgba8.clone(),
        }];
        scene.textures = vec![Texture {
            image: 0,
            wrap_s: Wrap::Repeat,
            wrap_t: Wrap::Repeat,
            nearest: true,
        }];
        let (camera, settings) = unit_quad_view(SIZE, 0);
        render(ctx, &Arc::new(scene), settings, &camera, 16)
    };
    // The specification's transform, and the texel a UV lands in under repeat wrapping.
    let expected_texel = |t: &TextureTransform, uv: Vec2| -> usize {
        let (s, c) = t.rotation.sin_cos();
        let scaled = uv * t.scale;
        let rotated = Vec2::new(c * scaled.x + s * scaled.y, -s * scaled.x + c * scaled.y);
        let moved = rotated + t.offset;
        let texel = |x: f32| ((x - x.floor()) * 2.0).floor().min(1.0) as usize;
        texel(moved.y) * 2 + texel(moved.x)
    };
    let (ctx, _gpu) = gpu();
    for transform in [
        TextureTransform::IDENTITY,
        TextureTransform {
            offset: Vec2::new(0.25, -0.1),
            rotation: 0.4,
            scale: Vec2::new(1.5, 0.75),
            tex_coord: None,
        },
    ] {
        let image = render_with(&ctx, transform);
        let (mut compared, mut wrong) = (0, Vec::new());
        for py in 0..SIZE {
            for px in 0..SIZE {
                // UV at a point of the pixel: the quad fills the image, so UV = position in the image.
                let uv = |fx: f32, fy: f32| {
                    Vec2::new(
                        (px as f32 + fx) / SIZE as f32,
                        (py as f32 + fy) / SIZE as f32,
                    )
                };
                let corners = [
                    (0.02, 0.02),
                    (0.98, 0.02),
                    (0.02, 0.98),
                    (0.98, 0.98),
                    (0.5, 0.5),
                ];
                let texels: Vec<usize> = corners
                    .iter()
                    .map(|&(fx, fy)| expected_texel(&transform, uv(fx, fy)))
                    .collect();
                if texels.iter().any(|&t| t != texels[0]) {
                    continue;
                }
                compared += 1;
                let got = image[(py * SIZE + px) as usize];
                let want = colours[texels[0]];
                if (0..3).any(|c| (got[c] - want[c]).abs() > 1e-3) {
                    wrong.push((px, py, got, want));
                }
            }
        }
        assert!(
            compared > SIZE * SIZE / 2,
            "{transform:?}: only {compared} pixels compared"
        );
        assert!(
            wrong.is_empty(),
            "{transform:?}: {} of {compared} pixels show the wrong texel, e.g. {:?}",
            wrong.len(),
            &wrong[..wrong.len().min(5)]
        );
    }
}

/// KHR_texture_transform on a normal map: the tangent-space normals turn with the image. A flat quad (tangent
/// +x, bitangent +y, glTF's v down the image) carries a constant normal map tilted towards the image's right
/// (+x in the texel); rotated by 90 degrees the image turns clockwise on the surface, so its right points down
/// the quad and the shading normal must tilt towards -y. Lit by a directional light from below the camera,
/// the rotated map must shade exactly like an unrotated map whose texel already points down, and unlike the
/// texel taken unturned or turned the other way (what a missing or sign-flipped correction gives).
#[test]
fn texture_transform_turns_normal_map_texels() {
    use raykin::scene::{
        Image, Material, NodeData, NodeTransform, PunctualKind, PunctualLight, Texture, TextureRef,
        TextureTransform, Wrap,
    };
    use std::f32::consts::FRAC_PI_2;
    const SIZE: u32 = 16;
    // Texel bytes of a tangent-space normal: 204 -> +0.6, 51 -> -0.6, 128 -> +1/255, 230 -> 0.804.
    let right = [204u8, 128, 230];
    let down = [128u8, 51, 230];
    let up = [128u8, 204, 230];
    let quad = raykin::scene::MeshData {
        uv0: Some(vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(0.0, 1.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(1.0, 0.0),
        ]),
        normals: Some(vec![Vec3::Z; 4]),
        tangents: Some(vec![glam::Vec4::new(1.0, 0.0, 0.0, 1.0); 4]),
        ..quad_mesh(
            [
                Vec3::new(-1.0, 1.0, 0.0),
                Vec3::new(-1.0, -1.0, 0.0),
                Vec3::new(1.0, -1.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
            ],
            0,
        )
    };
    let render_with = |ctx: &raykin::gpu::GpuContext, texel: [u8; 3], rotation: f32| {
        let mut scene = raykin::scene::procedural::scene_from_meshes(
            "rotated normal map",
            vec![(quad.clone(), Default::default())],
            vec![Material {
                name: "bumpy".into(),
                base_color: glam::Vec4::new(0.8, 0.8, 0.8, 1.0),
                metallic: 0.0,
                roughness: 1.0,
                normal_texture: Some(TextureRef {
                    texture: 0,
                    tex_coord: 0,
                    transform: TextureTransform {
                        rotation,
                        ..TextureTransform::IDENTITY
                    },
                }),
                ..Default::default()
            }],
        );
        scene.images = vec![Image {
            name: "constant normal".into(),
            width: 2,
            height: 2,
            rgba8: [texel[0], texel[1], texel[2], 255].repeat(4),
        }];
        scene.textures = vec![Texture {
            image: 0,
            wrap_s: Wrap::Repeat,
            wrap_t: Wrap::Repeat,
            nearest: true,
        }];
        // A directional light shines along its node's -Z: turned 45 degrees about +X it travels along
        // (0, 1, -1), i.e. it comes from below the camera.
        scene.lights = vec![PunctualLight {
            name: "from below".into(),
            kind: PunctualKind::Directional,
            color: Vec3::ONE,
            intensity: 3.0,
            range: None,
        }];
        scene.nodes.push(NodeData {
            name: "light".into(),
            transform: NodeTransform {
                rotation: glam::Quat::from_rotation_x(std::f32::consts::FRAC_PI_4),
                ..Default::default()
            },
            light: Some(0),
            ..Default::default()
        });
        scene.roots.push(scene.nodes.len() - 1);
        let (camera, settings) = unit_quad_view(SIZE, 1);
        render(ctx, &Arc::new(scene), settings, &camera, 2)
    };
    let mean = |img: &[[f32; 3]]| img.iter().map(|p| p[1] as f64).sum::<f64>() / img.len() as f64;
    let (ctx, _gpu) = gpu();
    let rotated = render_with(&ctx, right, FRAC_PI_2);
    let expected = render_with(&ctx, down, 0.0);
    let unturned = render_with(&ctx, right, 0.0);
    let turned_back = render_with(&ctx, up, 0.0);
    assert_all_finite(&rotated, "rotated normal map");
    let worst = rotated
        .iter()
        .zip(&expected)
        .map(|(a, b)| (a[1] - b[1]).abs() / b[1].max(1e-3))
        .fold(0.0f32, f32::max);
    let (m_rot, m_exp, m_unturned, m_back) = (
        mean(&rotated),
        mean(&expected),
        mean(&unturned),
        mean(&turned_back),
    );
    eprintln!(
        "mean green: rotated {m_rot:.4}, pre-rotated texel {m_exp:.4}, unturned {m_unturned:.4}, turned the other way {m_back:.4}; worst pixel {worst:.2e}"
    );
    // The alternatives are far apart (the normal's tilt decides the cosine), so the comparison discriminates.
    assert!(m_exp > 0.05, "the quad is lit: {m_exp}");
    assert!(
        m_unturned < 0.8 * m_exp && m_back < 0.8 * m_unturned,
        "tilts shade apart: down {m_exp}, right {m_unturned}, up {m_back}"
    );
    assert!(
        worst < 1e-3,
        "the rotated normal map shades unlike the pre-rotated texel: worst pixel off by {worst:.2e} (means: rotated {m_rot}, expected {m_exp}, unturned {m_unturned}, turned the other way {m_back})"
    );
}

/// A `size` x `size` view in which the unit quad at z = 0 (x, y in -1..1) exactly fills a 90-degree view from
/// distance 1, in black, with paths of `max_depth` bounces.
fn unit_quad_view(size: u32, max_depth: u32) -> (CameraChoice, RenderSettings) {
    let camera = CameraChoice::LookAt {
        eye: Vec3::new(0.0, 0.0, 1.0),
        target: Vec3::ZERO,
        yfov: 90f32.to_radians(),
    };
    let settings = RenderSettings {
        width: size,
        height: size,
        max_depth,
        environment: Environment::Constant([0.0; 3]),
        ..Default::default()
    };
    (camera, settings)
}
