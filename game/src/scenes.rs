//! The scenes the commands know by name, in one place for `render`, `view` and `bench`: the Cornell box built
//! into the binary, and the named scenes of the shared assets folder, each with a FIXED camera and environment
//! (bench figures compare across commits, and an automatic framing would move whenever framing code or an
//! asset's bounds change). Also loading a scene file with its warnings printed.

use anyhow::{Context, Result};
use glam::Vec3;
use raykin::animation::AnimationPlayer;
use raykin::camera::CameraChoice;
use raykin::render::Environment;
use raykin::scene::{LoadOptions, SceneAsset};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The scene shipped inside the binary (assets/default/): the Cornell box.
pub const DEFAULT_SCENE: &[u8] = include_bytes!("../../assets/default/CornellBox.glb");

/// A camera written down: where it stands, what it looks at, its vertical field of view.
pub struct FixedView {
    eye: [f32; 3],
    target: [f32; 3],
    yfov_deg: f32,
}

impl FixedView {
    pub fn camera(&self) -> CameraChoice {
        CameraChoice::LookAt {
            eye: Vec3::from(self.eye),
            target: Vec3::from(self.target),
            yfov: self.yfov_deg.to_radians(),
        }
    }
}

/// Where a named scene comes from.
pub enum Source {
    /// A file, relative to the shared assets folder.
    File(&'static str),
    /// `raykin::animation::crowd_scene`: 64 CesiumMan + 32 Fox, animated.
    Crowd,
    /// `raykin::animation::interior_scene`: CesiumMan and the Fox walking in the Cornell box, lit by its
    /// light, with a lamp the motion bench switches on.
    Interior,
    /// `raykin::animation::seed_interior_scene`: the crowd, the 1M-triangle spheres and FlightHelmets in a hall
    /// lit by ceiling panels (~1.6M triangles).
    SeedInterior,
    /// A file of this repository (the light tests' scenes, in tests/reference/lights).
    Repo(&'static str),
    /// A scene made in code by `raykin::scene::procedural` (the many-lights field, the furnace, the grazing
    /// light).
    Generated(fn() -> SceneAsset),
}

/// An environment map of this repository, turned by `rotation_degrees` (a scene's fixed environment).
pub struct RepoMap {
    pub path: &'static str,
    pub rotation_degrees: f32,
}

/// A file of this repository: relative to the working directory (a binary carried to another machine runs
/// from the repository root), else to the repository it was built from.
pub fn repo_path(rel: &str) -> PathBuf {
    let here = PathBuf::from(rel);
    if here.exists() {
        return here;
    }
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(rel)
}

pub struct NamedScene {
    pub name: &'static str,
    pub source: Source,
    pub view: FixedView,
    /// The environment, unless `environment_map` names one.
    environment: Environment,
    environment_map: Option<RepoMap>,
}

/// A named scene loaded: the asset, the animation players to attach (the crowd's), and the files whose bytes
/// define it (the bench's reference cache hashes them).
pub struct LoadedNamedScene {
    pub scene: Arc<SceneAsset>,
    pub players: Vec<(usize, AnimationPlayer)>,
    pub source_files: Vec<PathBuf>,
    /// A light the motion bench switches on mid-run: its material and emitted radiance.
    pub switchable_light: Option<(usize, Vec3)>,
}

// Cameras: the Cornell box's is the classic one (and the Mitsuba reference test's); FlightHelmet's and the
// spheres' are the automatic framings of 2026-11-22 (commit b8db256) written down; the crowd's looks over the
// 96 figures from the front (the automatic framing fitted the whole 40 m ground and left them a few pixels).

pub const CORNELL: NamedScene = NamedScene {
    name: "cornell",
    source: Source::File("CornellBox/CornellBox.glb"),
    view: FixedView {
        eye: [-278.0, 273.0, 800.0],
        target: [-278.0, 273.0, 0.0],
        yfov_deg: 39.3077,
    },
    environment: Environment::Constant([0.0; 3]),
    environment_map: None,
};

pub const FLIGHT_HELMET: NamedScene = NamedScene {
    name: "flight-helmet",
    source: Source::File("FlightHelmet/glTF/FlightHelmet.gltf"),
    view: FixedView {
        eye: [-0.0204, 0.4244, 1.1720],
        target: [-0.0204, 0.3580, 0.0142],
        yfov_deg: 45.0,
    },
    environment: Environment::Sky,
    environment_map: None,
};

pub const SPHERES: NamedScene = NamedScene {
    name: "spheres",
    source: Source::File("MetalRoughSpheresNoTextures/glTF-Binary/MetalRoughSpheresNoTextures.glb"),
    view: FixedView {
        eye: [0.002776, 0.003580, 0.013095],
        target: [0.002776, 0.002742, -0.0015],
        yfov_deg: 45.0,
    },
    environment: Environment::Sky,
    environment_map: None,
};

pub const CROWD: NamedScene = NamedScene {
    name: "crowd",
    source: Source::Crowd,
    view: FixedView {
        eye: [0.0, 6.0, 18.0],
        target: [0.0, 0.5, 0.0],
        yfov_deg: 45.0,
    },
    environment: Environment::Sky,
    environment_map: None,
};

/// The animated interior, seen through the Cornell box's classic camera.
pub const INTERIOR: NamedScene = NamedScene {
    name: "interior",
    source: Source::Interior,
    view: CORNELL.view,
    environment: Environment::Constant([0.0; 3]),
    environment_map: None,
};

/// Importance sampling of an environment map with a small, very bright sun (issue 15's >= 5x target): the
/// Mitsuba reference scene of tests/engine/lights_reference.rs, under its 64x33 sky whose sun is one texel of
/// radiance ~900, turned 30 degrees.
pub const ENV_LIT: NamedScene = NamedScene {
    name: "env-lit",
    source: Source::Repo("tests/reference/lights/envmap.gltf"),
    view: FixedView {
        eye: [0.0, 2.2, 5.0],
        target: [0.0, 0.6, 0.0],
        yfov_deg: 40.0,
    },
    environment: Environment::Constant([0.0; 3]),
    environment_map: Some(RepoMap {
        path: "tests/reference/lights/sunny_64x33.exr",
        rotation_degrees: 30.0,
    }),
};

/// 400 emitters (800 triangles) of which a few light each point: power vs tree light sampling.
pub const MANY_LIGHTS: NamedScene = NamedScene {
    name: "many-lights",
    source: Source::Generated(|| raykin::scene::procedural::light_field(20)),
    view: FixedView {
        eye: [0.0, 9.0, 20.0],
        target: [0.0, 0.0, 2.0],
        yfov_deg: 45.0,
    },
    environment: Environment::Constant([0.0; 3]),
    environment_map: None,
};

/// The white furnace (issue 17's scene classes): three spheres of base colour 1 under a constant environment of
/// 1, every path's light from BSDF sampling.
pub const FURNACE: NamedScene = NamedScene {
    name: "furnace",
    source: Source::Generated(raykin::scene::procedural::white_furnace),
    view: FixedView {
        eye: [0.0, 1.0, 7.0],
        target: [0.0, 0.0, 0.0],
        yfov_deg: 40.0,
    },
    environment: Environment::Constant([1.0; 3]),
    environment_map: None,
};

/// Grazing light at 1e4 coordinates (issue 17's scene classes): objects on a floor lit by a panel seen edge-on,
/// 1.3-4.5 degrees above the horizon, all of it about 1e4 from the origin, under a dim sky
/// (`raykin::scene::procedural::grazing_light`).
pub const GRAZING: NamedScene = NamedScene {
    name: "grazing",
    source: Source::Generated(raykin::scene::procedural::grazing_light),
    view: FixedView {
        eye: [10300.0, 10250.0, -9550.0],
        target: [9980.0, 10020.0, -10040.0],
        yfov_deg: 40.0,
    },
    environment: Environment::Constant([0.03; 3]),
    environment_map: None,
};

/// The seed-like workload (issue 17): 1.64M triangle instances in a hall lit by six ceiling panels, the crowd walking.
pub const SEED_INTERIOR: NamedScene = NamedScene {
    name: "seed-interior",
    source: Source::SeedInterior,
    view: FixedView {
        eye: [0.0, 4.5, 16.0],
        target: [0.0, 2.0, -6.0],
        yfov_deg: 60.0,
    },
    environment: Environment::Constant([0.0; 3]),
    environment_map: None,
};

const NAMED: &[&NamedScene] = &[
    &CORNELL,
    &FLIGHT_HELMET,
    &SPHERES,
    &ENV_LIT,
    &MANY_LIGHTS,
    &FURNACE,
    &GRAZING,
    &INTERIOR,
    &CROWD,
    &SEED_INTERIOR,
];

/// The named scene called `name`, if any.
pub fn named(name: &str) -> Option<&'static NamedScene> {
    NAMED.iter().copied().find(|n| n.name == name)
}

/// The names, for messages.
pub fn names() -> Vec<&'static str> {
    NAMED.iter().map(|n| n.name).collect()
}

impl NamedScene {
    pub fn camera(&self) -> CameraChoice {
        self.view.camera()
    }

    /// The scene's fixed environment.
    pub fn environment(&self) -> Environment {
        match &self.environment_map {
            Some(map) => Environment::Map(raykin::environment::MapSettings {
                path: repo_path(map.path),
                rotation_degrees: map.rotation_degrees,
                strength: 1.0,
            }),
            None => self.environment.clone(),
        }
    }

    /// Loads the scene from the shared assets folder `assets`.
    pub fn load(&self, assets: &Path) -> Result<LoadedNamedScene> {
        let context = || format!("scene `{}` (from --assets {})", self.name, assets.display());
        Ok(match self.source {
            Source::File(relative) => {
                let path = assets.join(relative);
                LoadedNamedScene {
                    scene: load_scene(&path, &LoadOptions::default()).with_context(context)?,
                    players: Vec::new(),
                    source_files: gltf_files(&path),
                    switchable_light: None,
                }
            }
            Source::Crowd => {
                let crowd = raykin::animation::crowd_scene(assets).with_context(context)?;
                LoadedNamedScene {
                    scene: Arc::new(crowd.scene),
                    players: crowd.players,
                    // The two files `crowd_scene` composes.
                    source_files: [
                        "CesiumMan/glTF-Binary/CesiumMan.glb",
                        "Fox/glTF-Binary/Fox.glb",
                    ]
                    .iter()
                    .map(|f| assets.join(f))
                    .collect(),
                    switchable_light: None,
                }
            }
            Source::Interior => {
                let interior = raykin::animation::interior_scene(assets).with_context(context)?;
                LoadedNamedScene {
                    scene: Arc::new(interior.scene),
                    players: interior.players,
                    source_files: [
                        "CornellBox/CornellBox.glb",
                        "CesiumMan/glTF-Binary/CesiumMan.glb",
                        "Fox/glTF-Binary/Fox.glb",
                    ]
                    .iter()
                    .map(|f| assets.join(f))
                    .collect(),
                    switchable_light: Some((interior.lamp_material, interior.lamp_radiance)),
                }
            }
            Source::SeedInterior => {
                let hall = raykin::animation::seed_interior_scene(assets).with_context(context)?;
                LoadedNamedScene {
                    scene: Arc::new(hall.scene),
                    players: hall.players,
                    source_files: [
                        "CesiumMan/glTF-Binary/CesiumMan.glb",
                        "Fox/glTF-Binary/Fox.glb",
                        "FlightHelmet/glTF/FlightHelmet.gltf",
                        "MetalRoughSpheresNoTextures/glTF-Binary/MetalRoughSpheresNoTextures.glb",
                    ]
                    .iter()
                    .map(|f| assets.join(f))
                    .chain([repo_path("engine/src/animation/seed_interior.rs")])
                    .collect(),
                    switchable_light: None,
                }
            }
            Source::Repo(relative) => {
                let path = repo_path(relative);
                let mut source_files = gltf_files(&path);
                source_files.extend(self.environment_map.as_ref().map(|m| repo_path(m.path)));
                LoadedNamedScene {
                    scene: load_scene(&path, &LoadOptions::default()).with_context(context)?,
                    players: Vec::new(),
                    source_files,
                    switchable_light: None,
                }
            }
            // The generator's source stands in for a file: editing it invalidates cached references.
            Source::Generated(generate) => LoadedNamedScene {
                scene: Arc::new(generate()),
                players: Vec::new(),
                source_files: vec![repo_path("engine/src/scene/procedural.rs")],
                switchable_light: None,
            },
        })
    }
}

/// The embedded Cornell box, loaded.
pub fn embedded_scene() -> Result<SceneAsset> {
    let scene = raykin::scene::load_gltf_slice(
        DEFAULT_SCENE,
        Path::new("."),
        Path::new("<embedded default scene>"),
        &LoadOptions::default(),
    )?;
    report_warnings(&scene);
    Ok(scene)
}

/// The embedded box is the `cornell` scene's model: the same classic view.
pub fn embedded_camera() -> CameraChoice {
    CORNELL.camera()
}

/// A glTF file, its warnings printed to stderr.
pub fn load_scene(path: &Path, options: &LoadOptions) -> Result<Arc<SceneAsset>> {
    let scene = raykin::scene::load_gltf(path, options)?;
    report_warnings(&scene);
    Ok(Arc::new(scene))
}

/// Each of the scene's warnings, once, as one line (the loader only collects them).
pub fn report_warnings(scene: &SceneAsset) {
    for w in &scene.warnings {
        eprintln!("raykin: warning: {}: {w}", scene.source);
    }
}

/// The glTF file and, for a .gltf, the files beside it (buffers, textures).
pub fn gltf_files(path: &Path) -> Vec<PathBuf> {
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
