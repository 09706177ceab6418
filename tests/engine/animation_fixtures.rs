//! Animation, skinning and morphing against the independent numpy reference (tests/reference/skinning),
//! through the real ECS systems (animate -> propagate_transforms -> deform_meshes) on a GPU-less world,
//! plus the keyframe sampler cases and bad-input handling.

use crate::common::{repo_root, shared_assets};
use base64::Engine as _;
use glam::{Mat4, Quat, Vec3};
use raykin::animation::{AnimationPlayer, DeformedMeshes, Sampled, cpu_app, sample_channel};
use raykin::scene::{
    AnimationChannel, ChannelValues, GlobalTransform, Interpolation, LoadOptions, SceneAsset,
    SceneNodes, SceneRoot, SkinnedMesh, load_gltf, load_gltf_slice,
};
use serde_json::Value;
use std::path::Path;
use std::sync::Arc;

fn read_json(rel: &str) -> Value {
    let path = repo_root().join(rel);
    serde_json::from_str(
        &std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display())),
    )
    .unwrap()
}

/// World-space positions of every vertex of every mesh node, after posing `scene` at (clip, time).
struct Posed {
    app: bevy_app::App,
    scene: Arc<SceneAsset>,
}

impl Posed {
    fn new(scene: Arc<SceneAsset>, clip: usize, time: f32) -> Self {
        let mut app = cpu_app(scene.clone());
        let world = app.world_mut();
        let root = world
            .query_filtered::<bevy_ecs::entity::Entity, bevy_ecs::query::With<SceneRoot>>()
            .single(world)
            .unwrap();
        world
            .entity_mut(root)
            .insert(AnimationPlayer::paused_at(clip, time));
        app.update();
        Self { app, scene }
    }

    fn node_positions(&mut self, node: usize) -> Vec<Vec3> {
        let world = self.app.world_mut();
        let root = world
            .query_filtered::<bevy_ecs::entity::Entity, bevy_ecs::query::With<SceneRoot>>()
            .single(world)
            .unwrap();
        let e = world.get::<SceneNodes>(root).unwrap().0[node];
        let global = world.get::<GlobalTransform>(e).unwrap().0;
        let skinned = world.get::<SkinnedMesh>(e).is_some();
        let mesh = self.scene.nodes[node].mesh.unwrap();
        let deformed = world
            .resource::<DeformedMeshes>()
            .meshes
            .get(mesh)
            .cloned()
            .flatten();
        match deformed {
            Some(d) if skinned => d.positions,
            Some(d) => d
                .positions
                .iter()
                .map(|p| global.transform_point3(*p))
                .collect(),
            None => self.scene.meshes[mesh]
                .positions
                .iter()
                .map(|p| global.transform_point3(*p))
                .collect(),
        }
    }
}

fn check_fixture_file(rel: &str, filter: impl Fn(&str) -> bool) -> usize {
    let fixtures = read_json(rel);
    let mut checked = 0;
    let mut cache: Vec<(String, Arc<SceneAsset>)> = Vec::new();
    for case in fixtures["cases"].as_array().unwrap() {
        let asset = case["asset"].as_str().unwrap();
        if !filter(asset) {
            continue;
        }
        let scene = match cache.iter().find(|(a, _)| a == asset) {
            Some((_, s)) => s.clone(),
            None => {
                let s = Arc::new(
                    load_gltf(
                        repo_root().join(asset),
                        &LoadOptions {
                            skip_images: true,
                            ..Default::default()
                        },
                    )
                    .unwrap(),
                );
                cache.push((asset.to_string(), s.clone()));
                s
            }
        };
        let clip = case["animation"].as_u64().unwrap() as usize;
        let time = case["time"].as_f64().unwrap() as f32;
        let mut posed = Posed::new(scene.clone(), clip, time);
        let mut largest = 1.0f64;
        for node in case["nodes"].as_array().unwrap() {
            for prim in node["primitives"].as_array().unwrap() {
                for p in prim["positions"].as_array().unwrap() {
                    for c in p.as_array().unwrap() {
                        largest = largest.max(c.as_f64().unwrap().abs());
                    }
                }
            }
        }
        let tol = 1e-4 * largest;
        let mut worst = 0.0f64;
        for node in case["nodes"].as_array().unwrap() {
            let n = node["node"].as_u64().unwrap() as usize;
            let positions = posed.node_positions(n);
            let mesh = &scene.meshes[scene.nodes[n].mesh.unwrap()];
            for prim in node["primitives"].as_array().unwrap() {
                let p = prim["primitive"].as_u64().unwrap() as usize;
                let range = &mesh.primitives[p];
                assert_eq!(
                    range.vertex_count as u64,
                    prim["vertex_count"].as_u64().unwrap(),
                    "{asset} node {n} primitive {p}"
                );
                for (v, expected) in prim["vertex_indices"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .zip(prim["positions"].as_array().unwrap())
                {
                    let v = v.as_u64().unwrap() as usize;
                    let got = positions[range.vertex_offset as usize + v];
                    let e = expected.as_array().unwrap();
                    for k in 0..3 {
                        let d = (got[k] as f64 - e[k].as_f64().unwrap()).abs();
                        worst = worst.max(d);
                        assert!(
                            d <= tol,
                            "{asset} clip {clip} t={time} node {n} prim {p} vertex {v}: got {got:?}, expected {e:?} (tol {tol:e})"
                        );
                    }
                    checked += 1;
                }
            }
        }
        eprintln!("{asset} clip {clip} t={time}: worst |d| {worst:.3e} (tol {tol:.1e})");
    }
    checked
}

macro_rules! fixture_test {
    ($name:ident, $needle:expr) => {
        #[test]
        fn $name() {
            let n = check_fixture_file("tests/reference/skinning/fixtures.json", |a| {
                a.contains($needle)
            });
            assert!(n > 0, "no fixture vertices for {}", $needle);
        }
    };
}

fixture_test!(rigged_simple_matches_reference, "RiggedSimple");
fixture_test!(cesium_man_matches_reference, "CesiumMan");
fixture_test!(fox_matches_reference, "Fox");
fixture_test!(robot_expressive_matches_reference, "RobotExpressive");
fixture_test!(animated_morph_cube_matches_reference, "AnimatedMorphCube");
fixture_test!(simple_morph_matches_reference, "SimpleMorph");

#[test]
fn synthetic_skin_morph_matches_reference() {
    let n = check_fixture_file("tests/reference/skinning/synthetic_fixtures.json", |_| true);
    assert!(n > 0);
    // The hand-derived vertices too.
    let fixtures = read_json("tests/reference/skinning/synthetic_fixtures.json");
    let scene = Arc::new(
        load_gltf(
            repo_root().join("tests/reference/skinning/synthetic_skin_morph.gltf"),
            &LoadOptions::default(),
        )
        .unwrap(),
    );
    for h in fixtures["hand_checks"].as_array().unwrap() {
        let mut posed = Posed::new(
            scene.clone(),
            h["animation"].as_u64().unwrap() as usize,
            h["time"].as_f64().unwrap() as f32,
        );
        let got = posed.node_positions(h["node"].as_u64().unwrap() as usize)
            [h["vertex"].as_u64().unwrap() as usize];
        let e: Vec<f32> = h["expected"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap() as f32)
            .collect();
        assert!(
            (got - Vec3::new(e[0], e[1], e[2])).abs().max_element() < 1e-4,
            "{h}: got {got:?}"
        );
    }
}

#[test]
fn interpolation_cases() {
    let cases = read_json("tests/reference/skinning/interp_cases.json");
    let mut by_name = std::collections::HashMap::new();
    for case in cases["cases"].as_array().unwrap() {
        let interpolation = match case["interpolation"].as_str().unwrap() {
            "STEP" => Interpolation::Step,
            "LINEAR" => Interpolation::Linear,
            _ => Interpolation::CubicSpline,
        };
        let times: Vec<f32> = case["input"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap() as f32)
            .collect();
        let out: Vec<f32> = case["output"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap() as f32)
            .collect();
        let components = case["components"].as_u64().unwrap() as usize;
        let kind = case["type"].as_str().unwrap();
        let values = match kind {
            "vec3" => ChannelValues::Translation(out.chunks(3).map(Vec3::from_slice).collect()),
            "quat" => ChannelValues::Rotation(out.chunks(4).map(Quat::from_slice).collect()),
            _ => ChannelValues::Weights {
                values: out.clone(),
                count: components,
            },
        };
        let channel = AnimationChannel {
            node: 0,
            interpolation,
            times,
            values,
        };
        channel.validate().unwrap();
        let name = case["name"].as_str().unwrap().to_string();
        for q in case["queries"].as_array().unwrap() {
            let t = q["t"].as_f64().unwrap() as f32;
            let e: Vec<f32> = q["expected"]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_f64().unwrap() as f32)
                .collect();
            let got = sampled_as_expected(sample_channel(&channel, t), &e);
            assert_eq!(got.len(), e.len(), "{name} t={t}");
            for (g, x) in got.iter().zip(&e) {
                assert!(
                    (g - x).abs() <= 1e-5 * x.abs().max(1.0),
                    "{name} t={t}: got {got:?}, expected {e:?}"
                );
            }
        }
        by_name.insert(name, channel);
    }
    for h in cases["hand_checks"].as_array().unwrap() {
        let channel = &by_name[h["case"].as_str().unwrap()];
        let t = h["t"].as_f64().unwrap() as f32;
        let e: Vec<f32> = h["expected"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap() as f32)
            .collect();
        let got = sampled_as_expected(sample_channel(channel, t), &e);
        for (g, x) in got.iter().zip(&e) {
            assert!(
                (g - x).abs() <= 1e-5 * x.abs().max(1.0),
                "hand check {h}: got {got:?}"
            );
        }
    }
}

#[test]
fn player_modes_loop_once_pingpong() {
    use raykin::animation::PlayMode;
    let mut p = AnimationPlayer::new(0);
    p.time = 2.5;
    assert!((p.local_time(2.0) - 0.5).abs() < 1e-6);
    p.mode = PlayMode::Once;
    assert_eq!(p.local_time(2.0), 2.0);
    p.mode = PlayMode::PingPong;
    assert!((p.local_time(2.0) - 1.5).abs() < 1e-6);
    p.time = f32::NAN;
    assert_eq!(p.local_time(2.0), 0.0);
}

#[test]
fn several_players_at_once_with_explicit_clock() {
    // Two copies of RiggedSimple, one held at its first key, one playing from 0 for 30 frames of 1/60 s.
    let scene = Arc::new(
        load_gltf(
            shared_assets().join("RiggedSimple/glTF-Binary/RiggedSimple.glb"),
            &LoadOptions::default(),
        )
        .unwrap(),
    );
    let (crowd, copies) = raykin::scene::compose::compose(
        "two",
        &[
            (scene.clone(), Default::default()),
            (scene.clone(), Default::default()),
        ],
    );
    assert_eq!(
        crowd.meshes.len(),
        2,
        "the skinned mesh is duplicated per copy"
    );
    let crowd = Arc::new(crowd);
    let mut app = cpu_app(crowd.clone());
    let world = app.world_mut();
    let root = world
        .query_filtered::<bevy_ecs::entity::Entity, bevy_ecs::query::With<SceneRoot>>()
        .single(world)
        .unwrap();
    raykin::animation::attach_players(
        world,
        root,
        &[
            (
                copies[0].group_node,
                AnimationPlayer::paused_at(copies[0].first_clip, 0.0),
            ),
            (
                copies[1].group_node,
                AnimationPlayer::new(copies[1].first_clip),
            ),
        ],
    );
    for _ in 0..31 {
        app.update();
    }
    let d = app.world().resource::<DeformedMeshes>();
    let a = d.meshes[0].as_ref().unwrap();
    let b = d.meshes[1].as_ref().unwrap();
    assert_ne!(
        a.positions, b.positions,
        "the playing copy moved away from the held one"
    );
    // Frame 31 shows the pose at 30/60 s: it equals a held pose at 0.5 s.
    let mut posed = Posed::new(scene.clone(), 0, 30.0 / 60.0);
    let expected = posed.node_positions(scene.nodes.iter().position(|n| n.mesh.is_some()).unwrap());
    for (g, e) in b.positions.iter().zip(&expected) {
        assert!((*g - *e).abs().max_element() < 1e-4, "{g:?} vs {e:?}");
    }
}

// ---------- bad input ----------

struct Bad {
    joints: [u16; 4],
    weights: [f32; 4],
    ibm: bool,
    times: [f32; 2],
    values: [f32; 6],
    extra: &'static str,
    output_count: usize,
}

impl Default for Bad {
    fn default() -> Self {
        Self {
            joints: [0; 4],
            weights: [1.0, 0.0, 0.0, 0.0],
            ibm: true,
            times: [0.0, 1.0],
            values: [0.0, 0.0, 1.0, 0.0, 1.0, 1.0],
            extra: "",
            output_count: 2,
        }
    }
}

/// A skinned triangle (node 0 = mesh, node 1 = joint) with a translation clip on the joint.
fn bad_gltf(b: &Bad) -> Vec<u8> {
    let mut bin: Vec<u8> = Vec::new();
    let f = |bin: &mut Vec<u8>, v: &[f32]| v.iter().for_each(|x| bin.extend(x.to_le_bytes()));
    f(&mut bin, &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]); // 0..36 positions
    for _ in 0..3 {
        b.joints.iter().for_each(|j| bin.extend(j.to_le_bytes())); // 36..60
    }
    for _ in 0..3 {
        f(&mut bin, &b.weights); // 60..108
    }
    f(
        &mut bin,
        &Mat4::from_translation(Vec3::new(0.0, 0.0, -1.0)).to_cols_array(),
    ); // 108..172
    f(&mut bin, &b.times); // 172..180
    f(&mut bin, &b.values); // 180..204
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&bin)
    );
    let skin = if b.ibm {
        r#"{"joints":[1],"inverseBindMatrices":4}"#
    } else {
        r#"{"joints":[1]}"#
    };
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0,1]}}],
"nodes":[{{"mesh":0,"skin":0}},{{"translation":[0,0,1]}}{extra}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"JOINTS_0":1,"WEIGHTS_0":2}}}}]}}],
"skins":[{skin}],
"animations":[{{"channels":[{{"sampler":0,"target":{{"node":1,"path":"translation"}}}}],"samplers":[{{"input":5,"output":6}}]}}],
"buffers":[{{"byteLength":{len},"uri":"{uri}"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":24}},{{"buffer":0,"byteOffset":60,"byteLength":48}},
{{"buffer":0,"byteOffset":108,"byteLength":64}},{{"buffer":0,"byteOffset":172,"byteLength":8}},{{"buffer":0,"byteOffset":180,"byteLength":24}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
{{"bufferView":1,"componentType":5123,"count":3,"type":"VEC4"}},{{"bufferView":2,"componentType":5126,"count":3,"type":"VEC4"}},
{{"bufferView":3,"componentType":5126,"count":1,"type":"MAT4"}},{{"bufferView":3,"componentType":5126,"count":1,"type":"MAT4"}},
{{"bufferView":4,"componentType":5126,"count":2,"type":"SCALAR","min":[{t0}],"max":[{t1}]}},
{{"bufferView":5,"componentType":5126,"count":{oc},"type":"VEC3"}}]}}"#,
        extra = b.extra,
        len = bin.len(),
        t0 = b.times[0].min(b.times[1]),
        t1 = b.times[0].max(b.times[1]),
        oc = b.output_count,
    );
    json.into_bytes()
}

fn load_bad(b: &Bad) -> Result<SceneAsset, raykin::scene::SceneError> {
    load_gltf_slice(
        &bad_gltf(b),
        Path::new("."),
        Path::new("bad.gltf"),
        &LoadOptions::default(),
    )
}

/// Poses at t = 0.5 and returns the mesh's world-space positions; all must be finite.
fn pose_bad(scene: SceneAsset) -> Vec<Vec3> {
    let scene = Arc::new(scene);
    let clip = if scene.animations.is_empty() {
        usize::MAX
    } else {
        0
    };
    let mut posed = Posed::new(scene, clip, 0.5);
    let p = posed.node_positions(0);
    assert!(p.iter().all(|p| p.is_finite()), "{p:?}");
    p
}

#[test]
fn good_input_skins_as_expected() {
    let scene = load_bad(&Bad::default()).unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    // Joint at (0, 0.5, 1) at t = 0.5, inverse bind (0, 0, -1): vertices move by (0, 0.5, 0).
    let p = pose_bad(scene);
    assert!((p[1] - Vec3::new(1.0, 0.5, 0.0)).length() < 1e-6, "{p:?}");
}

#[test]
fn joint_index_out_of_range_is_ignored_with_warning() {
    let scene = load_bad(&Bad {
        joints: [7, 0, 0, 0],
        weights: [0.5, 0.5, 0.0, 0.0],
        ..Default::default()
    })
    .unwrap();
    assert!(
        scene.warnings.iter().any(|w| w.contains("outside skin")),
        "{:?}",
        scene.warnings
    );
    // The valid half of the weight is renormalised to 1.
    let p = pose_bad(scene);
    assert!((p[1] - Vec3::new(1.0, 0.5, 0.0)).length() < 1e-6, "{p:?}");
}

#[test]
fn all_zero_weights_follow_the_node() {
    let scene = load_bad(&Bad {
        weights: [0.0; 4],
        ..Default::default()
    })
    .unwrap();
    assert!(
        scene
            .warnings
            .iter()
            .any(|w| w.contains("no usable skin weight")),
        "{:?}",
        scene.warnings
    );
    let p = pose_bad(scene);
    assert_eq!(p[1], Vec3::new(1.0, 0.0, 0.0));
}

#[test]
fn unnormalised_weights_are_renormalised() {
    let scene = load_bad(&Bad {
        weights: [2.0, 0.0, 0.0, 0.0],
        ..Default::default()
    })
    .unwrap();
    let p = pose_bad(scene);
    assert!((p[1] - Vec3::new(1.0, 0.5, 0.0)).length() < 1e-6, "{p:?}");
}

#[test]
fn nan_keyframe_channel_is_skipped() {
    let scene = load_bad(&Bad {
        values: [0.0, 0.0, 1.0, 0.0, f32::NAN, 1.0],
        ..Default::default()
    })
    .unwrap();
    assert!(
        scene.warnings.iter().any(|w| w.contains("NaN")),
        "{:?}",
        scene.warnings
    );
    pose_bad(scene);
}

#[test]
fn non_increasing_times_channel_is_skipped() {
    let scene = load_bad(&Bad {
        times: [1.0, 0.5],
        ..Default::default()
    })
    .unwrap();
    assert!(
        scene
            .warnings
            .iter()
            .any(|w| w.contains("strictly increasing")),
        "{:?}",
        scene.warnings
    );
    pose_bad(scene);
}

#[test]
fn sampler_accessor_count_mismatch_is_an_error_or_skipped() {
    match load_bad(&Bad {
        output_count: 1,
        ..Default::default()
    }) {
        Ok(scene) => {
            assert!(
                scene
                    .warnings
                    .iter()
                    .any(|w| w.contains("mismatch") || w.contains("skipped")),
                "{:?}",
                scene.warnings
            );
            pose_bad(scene);
        }
        Err(e) => assert!(!e.to_string().is_empty()),
    }
}

#[test]
fn skin_without_inverse_bind_matrices_uses_identity() {
    let scene = load_bad(&Bad {
        ibm: false,
        ..Default::default()
    })
    .unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    // Identity inverse bind: vertex = joint global (0, 0.5, 1) x rest position.
    let p = pose_bad(scene);
    assert!((p[1] - Vec3::new(1.0, 0.5, 1.0)).length() < 1e-6, "{p:?}");
}

#[test]
fn cyclic_nodes_are_an_error() {
    let e = load_bad(&Bad {
        extra: r#",{"children":[3]},{"children":[2]}"#,
        ..Default::default()
    })
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("cycle") || e.contains("parent") || e.contains("valid"),
        "{e}"
    );
}

#[test]
fn missing_nodes_are_an_error() {
    let e = load_bad(&Bad {
        extra: r#",{"children":[9]}"#,
        ..Default::default()
    })
    .unwrap_err()
    .to_string();
    assert!(e.contains("bad.gltf"), "{e}");
}

#[test]
fn posing_a_scene_without_clip_is_harmless() {
    let mut scene = load_bad(&Bad::default()).unwrap();
    scene.animations.clear();
    pose_bad(scene);
}

#[test]
fn crowd_scene_skins_every_instance() {
    let crowd = raykin::animation::crowd_scene(shared_assets()).unwrap();
    assert_eq!(crowd.players.len(), 96);
    let skinned: Vec<usize> = (0..crowd.scene.meshes.len())
        .filter(|&m| crowd.scene.meshes[m].skin_weights.is_some())
        .collect();
    assert_eq!(skinned.len(), 96, "one skinned mesh per placed copy");
    let scene = Arc::new(crowd.scene);
    let mut app = cpu_app(scene.clone());
    let world = app.world_mut();
    let root = world
        .query_filtered::<bevy_ecs::entity::Entity, bevy_ecs::query::With<SceneRoot>>()
        .single(world)
        .unwrap();
    raykin::animation::attach_players(world, root, &crowd.players);
    app.update();
    let d = app.world().resource::<DeformedMeshes>();
    assert_eq!(d.changed.len(), 96);
    // Staggered times: the first two CesiumMan copies are in different poses (relative to their placement).
    let a = &d.meshes[skinned[0]].as_ref().unwrap().positions;
    let b = &d.meshes[skinned[1]].as_ref().unwrap().positions;
    let offset = b[0] - a[0];
    assert!(
        a.iter()
            .zip(b)
            .any(|(p, q)| (*q - *p - offset).length() > 1e-3)
    );
    assert!(a.iter().chain(b).all(|p| p.is_finite()));
}

/// A sampled value as a flat list, with a rotation's sign matched to the expected one (q and -q are the same
/// rotation).
fn sampled_as_expected(sampled: Sampled, expected: &[f32]) -> Vec<f32> {
    match sampled {
        Sampled::Translation(v) | Sampled::Scale(v) => v.to_array().to_vec(),
        Sampled::Rotation(r) => {
            let r = if r.dot(Quat::from_slice(expected)) < 0.0 {
                -r
            } else {
                r
            };
            r.to_array().to_vec()
        }
        Sampled::Weights(w) => w,
    }
}
