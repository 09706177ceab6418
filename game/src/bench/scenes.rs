//! The named bench scenes, each with a FIXED camera and environment so that figures compare across commits
//! (an automatic framing would move whenever framing code or an asset's bounds change).

use anyhow::{Context, Result};
use glam::Vec3;
use raykin::animation::AnimationPlayer;
use raykin::camera::CameraChoice;
use raykin::render::Environment;
use raykin::scene::{LoadOptions, NodeTransform, SceneAsset};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Where a named scene comes from, relative to the shared assets folder.
enum Source {
    File(&'static str),
    /// `raykin::scene::crowd_scene`: 64 CesiumMan + 32 Fox, animated.
    Crowd,
    /// A file in this repository (the light tests' scenes).
    Repo(&'static str),
    /// `raykin::scene::procedural::light_field(n)`: n x n small emissive squares over a floor.
    LightField(usize),
}

/// A file of this repository (the light scenes and their maps live in tests/reference/lights): relative to
/// the working directory (a binary carried to another machine runs from the repository root), else to the
/// repository it was built from.
fn repo_path(rel: &str) -> PathBuf {
    let here = PathBuf::from(rel);
    if here.exists() {
        return here;
    }
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(rel)
}

/// The environment-lit bench scene's map: a 64x33 sky whose sun is one texel of radiance ~900 (the Mitsuba
/// reference's), turned 30 degrees.
const SUNNY_MAP: &str = "tests/reference/lights/sunny_64x33.exr";

struct Named {
    name: &'static str,
    source: Source,
    eye: [f32; 3],
    target: [f32; 3],
    yfov_deg: f32,
    environment: Environment,
}

const SKY: Environment = Environment::Sky;

/// Cameras: the Cornell box's is the classic one (and the Mitsuba reference test's); FlightHelmet's and the
/// spheres' are the automatic framings of 2026-11-22 (commit b8db256) written down; the crowd's looks over the
/// 96 figures from the front (the automatic framing fitted the whole 40 m ground and left them a few pixels).
const NAMED: &[Named] = &[
    Named {
        name: "cornell",
        source: Source::File("CornellBox/CornellBox.glb"),
        eye: [-278.0, 273.0, 800.0],
        target: [-278.0, 273.0, 0.0],
        yfov_deg: 39.3077,
        environment: Environment::Constant([0.0; 3]),
    },
    Named {
        name: "flight-helmet",
        source: Source::File("FlightHelmet/glTF/FlightHelmet.gltf"),
        eye: [-0.0204, 0.4244, 1.1720],
        target: [-0.0204, 0.3580, 0.0142],
        yfov_deg: 45.0,
        environment: SKY,
    },
    Named {
        name: "spheres",
        source: Source::File(
            "MetalRoughSpheresNoTextures/glTF-Binary/MetalRoughSpheresNoTextures.glb",
        ),
        eye: [0.002776, 0.003580, 0.013095],
        target: [0.002776, 0.002742, -0.0015],
        yfov_deg: 45.0,
        environment: SKY,
    },
    // Importance sampling of an environment map with a small, very bright sun (issue 15's >= 5x target): the
    // Mitsuba reference scene of tests/lights_reference.rs.
    Named {
        name: "env-lit",
        source: Source::Repo("tests/reference/lights/envmap.gltf"),
        eye: [0.0, 2.2, 5.0],
        target: [0.0, 0.6, 0.0],
        yfov_deg: 40.0,
        environment: Environment::Constant([0.0; 3]),
    },
    // 400 emitters (800 triangles) of which a few light each point: power vs tree light sampling.
    Named {
        name: "many-lights",
        source: Source::LightField(20),
        eye: [0.0, 9.0, 20.0],
        target: [0.0, 0.0, 2.0],
        yfov_deg: 45.0,
        environment: Environment::Constant([0.0; 3]),
    },
    Named {
        name: "crowd",
        source: Source::Crowd,
        eye: [0.0, 6.0, 18.0],
        target: [0.0, 0.5, 0.0],
        yfov_deg: 45.0,
        environment: SKY,
    },
];

/// The names `--scene` accepts besides file paths.
pub fn named_scene_names() -> Vec<&'static str> {
    NAMED.iter().map(|n| n.name).collect()
}

/// The fixed camera of a named bench scene (the viewer opens `crowd` with it, so its offscreen timings frame
/// the same picture as the bench's).
pub fn named_camera(name: &str) -> Option<CameraChoice> {
    NAMED
        .iter()
        .find(|n| n.name == name)
        .map(|n| CameraChoice::LookAt {
            eye: Vec3::from(n.eye),
            target: Vec3::from(n.target),
            yfov: n.yfov_deg.to_radians(),
        })
}

/// A scene ready to bench: the asset, its fixed view, and what produced it (for reference-cache keys).
pub struct BenchScene {
    pub name: String,
    pub scene: Arc<SceneAsset>,
    pub camera: CameraChoice,
    pub environment: Environment,
    /// Animation players to attach to the scene's nodes (animated scenes only).
    pub players: Vec<(usize, AnimationPlayer)>,
    /// Files whose bytes define the scene (the reference cache hashes them).
    pub source_files: Vec<PathBuf>,
}

impl BenchScene {
    pub fn animated(&self) -> bool {
        !self.players.is_empty()
    }
}

/// A named scene (from `assets`) or a glTF file (automatic camera, sky).
pub fn resolve(spec: &str, assets: &Path) -> Result<BenchScene> {
    let Some(named) = NAMED.iter().find(|n| n.name == spec) else {
        let path = PathBuf::from(spec);
        if !path.exists() {
            anyhow::bail!(
                "--scene {spec}: no such file, and not a named bench scene ({})",
                named_scene_names().join(", ")
            );
        }
        let scene = crate::render_cmd::load_scene(&path)?;
        return Ok(BenchScene {
            name: path
                .file_stem()
                .map_or_else(|| spec.to_string(), |s| s.to_string_lossy().into_owned()),
            scene,
            camera: CameraChoice::Auto,
            environment: SKY,
            players: Vec::new(),
            source_files: gltf_files(&path),
        });
    };
    let camera = named_camera(named.name).unwrap_or_default();
    let (scene, players, source_files) = match named.source {
        Source::File(rel) => {
            let path = assets.join(rel);
            let scene = crate::render_cmd::load_scene(&path).with_context(|| {
                format!(
                    "bench scene `{}` (from --assets {})",
                    named.name,
                    assets.display()
                )
            })?;
            (scene, Vec::new(), gltf_files(&path))
        }
        Source::Crowd => {
            let crowd = raykin::scene::crowd_scene(assets).with_context(|| {
                format!("bench scene `crowd` (from --assets {})", assets.display())
            })?;
            let files = [
                "CesiumMan/glTF-Binary/CesiumMan.glb",
                "Fox/glTF-Binary/Fox.glb",
            ]
            .iter()
            .map(|f| assets.join(f))
            .collect();
            (Arc::new(crowd.scene), crowd.players, files)
        }
        Source::Repo(rel) => {
            let path = repo_path(rel);
            let scene = crate::render_cmd::load_scene(&path)
                .with_context(|| format!("bench scene `{}`", named.name))?;
            let mut files = gltf_files(&path);
            files.push(repo_path(SUNNY_MAP));
            (scene, Vec::new(), files)
        }
        // The generator's source stands in for a file: editing it invalidates cached references.
        Source::LightField(n) => (
            Arc::new(raykin::scene::procedural::light_field(n)),
            Vec::new(),
            vec![repo_path("engine/src/scene/procedural.rs")],
        ),
    };
    let environment = match named.source {
        Source::Repo(_) => Environment::Map(raykin::environment::MapSettings {
            path: repo_path(SUNNY_MAP),
            rotation_degrees: 30.0,
            strength: 1.0,
        }),
        _ => named.environment.clone(),
    };
    Ok(BenchScene {
        name: named.name.to_string(),
        scene,
        camera,
        environment,
        players,
        source_files,
    })
}

/// The glTF file and, for a .gltf, the files beside it (buffers, textures).
fn gltf_files(path: &Path) -> Vec<PathBuf> {
    let mut files = vec![path.to_path_buf()];
    let is_gltf = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gltf"));
    if let (true, Some(dir)) = (is_gltf, path.parent())
        && let Ok(entries) = std::fs::read_dir(dir)
    {
        let mut siblings: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.is_file() && p != path)
            .collect();
        siblings.sort();
        files.extend(siblings);
    }
    files
}

/// The asset the triangle-count scaling copies (one mesh, 15k triangles; textures are not needed to time
/// traversal).
pub const SCALING_ASSET: &str = "DamagedHelmet/glTF-Binary/DamagedHelmet.glb";

/// `copies` instances of one asset on a square grid facing +Z (a wall), with a camera that fits the wall
/// vertically: the static meshes are shared, so this is one BLAS under `copies` top-level instances.
pub fn instanced_grid(asset: &Arc<SceneAsset>, copies: usize) -> (SceneAsset, CameraChoice) {
    let side = (copies as f64).sqrt().ceil().max(1.0) as usize;
    let spacing = 2.5;
    let parts: Vec<(Arc<SceneAsset>, NodeTransform)> = (0..copies)
        .map(|i| {
            let (col, row) = ((i % side) as f32, (i / side) as f32);
            let centre = (side as f32 - 1.0) * 0.5;
            let placement = NodeTransform {
                translation: Vec3::new((col - centre) * spacing, (centre - row) * spacing, 0.0),
                ..Default::default()
            };
            (asset.clone(), placement)
        })
        .collect();
    let (scene, _) = raykin::scene::compose(&format!("{copies} instances"), &parts);
    let yfov = 45f32.to_radians();
    let half_height = side as f32 * spacing * 0.5;
    let distance = half_height / (yfov * 0.5).tan() + 1.5;
    let camera = CameraChoice::LookAt {
        eye: Vec3::new(0.0, 0.0, distance),
        target: Vec3::ZERO,
        yfov,
    };
    (scene, camera)
}

/// Loads the scaling asset without images (traversal time does not depend on texels).
pub fn load_scaling_asset(assets: &Path) -> Result<Arc<SceneAsset>> {
    let path = assets.join(SCALING_ASSET);
    let scene = raykin::scene::load_gltf(&path, &LoadOptions { skip_images: true })
        .with_context(|| format!("scaling asset (from --assets {})", assets.display()))?;
    Ok(Arc::new(scene))
}

/// CesiumMan, alone, with a fixed camera: the refit-vs-rebuild measurement walks it through its clip.
pub fn cesium_man(assets: &Path) -> Result<(Arc<SceneAsset>, CameraChoice)> {
    let path = assets.join("CesiumMan/glTF-Binary/CesiumMan.glb");
    let scene = crate::render_cmd::load_scene(&path)
        .with_context(|| format!("refit bench asset (from --assets {})", assets.display()))?;
    let camera = CameraChoice::LookAt {
        eye: Vec3::new(0.0, 0.8, 2.6),
        target: Vec3::new(0.0, 0.75, 0.0),
        yfov: 45f32.to_radians(),
    };
    Ok((scene, camera))
}
