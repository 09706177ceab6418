//! The scenes the bench measures: the named scenes of `crate::scenes` (fixed cameras, so figures compare
//! across commits) or glTF files, and the synthetic ones of the scaling and refit parts.

use crate::scenes::{gltf_files, load_scene};
use anyhow::{Context, Result};
use glam::Vec3;
use raykin::animation::AnimationPlayer;
use raykin::camera::CameraChoice;
use raykin::render::Environment;
use raykin::scene::{LoadOptions, NodeTransform, SceneAsset};
use std::path::{Path, PathBuf};
use std::sync::Arc;

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
    /// A light the motion bench switches on mid-run: its material and emitted radiance.
    pub switchable_light: Option<(usize, Vec3)>,
}

impl BenchScene {
    /// A scene with no players and no source files (built in memory, never cached).
    pub fn still(
        name: String,
        scene: Arc<SceneAsset>,
        camera: CameraChoice,
        environment: Environment,
    ) -> Self {
        Self {
            name,
            scene,
            camera,
            environment,
            players: Vec::new(),
            source_files: Vec::new(),
            switchable_light: None,
        }
    }

    pub fn animated(&self) -> bool {
        !self.players.is_empty()
    }
}

/// A named scene (from `assets`) or a glTF file (automatic camera, sky).
pub fn resolve(spec: &str, assets: &Path) -> Result<BenchScene> {
    if let Some(named) = crate::scenes::named(spec) {
        let loaded = named.load(assets)?;
        return Ok(BenchScene {
            name: named.name.to_string(),
            scene: loaded.scene,
            camera: named.camera(),
            environment: named.environment(),
            players: loaded.players,
            source_files: loaded.source_files,
            switchable_light: loaded.switchable_light,
        });
    }
    let path = PathBuf::from(spec);
    if !path.exists() {
        anyhow::bail!(
            "--scene {spec}: no such file, and not a named bench scene ({})",
            crate::scenes::names().join(", ")
        );
    }
    let name = path
        .file_stem()
        .map_or_else(|| spec.to_string(), |s| s.to_string_lossy().into_owned());
    Ok(BenchScene {
        source_files: gltf_files(&path),
        ..BenchScene::still(
            name,
            load_scene(&path, &LoadOptions::default())?,
            CameraChoice::Auto,
            Environment::Sky,
        )
    })
}

/// The scene called `name` among `loaded`, resolved and added to them when missing.
pub fn find_or_load<'a>(
    loaded: &'a mut Vec<BenchScene>,
    name: &str,
    assets: &Path,
) -> Result<&'a BenchScene> {
    let index = match loaded.iter().position(|s| s.name == name) {
        Some(i) => i,
        None => {
            loaded.push(resolve(name, assets)?);
            loaded.len() - 1
        }
    };
    Ok(&loaded[index])
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
    let scene = raykin::scene::load_gltf(
        &path,
        &LoadOptions {
            skip_images: true,
            ..Default::default()
        },
    )
    .with_context(|| format!("scaling asset (from --assets {})", assets.display()))?;
    Ok(Arc::new(scene))
}

/// CesiumMan, alone, with a fixed camera: the refit-vs-rebuild measurement walks it through its clip.
pub fn cesium_man(assets: &Path) -> Result<(Arc<SceneAsset>, CameraChoice)> {
    let path = assets.join("CesiumMan/glTF-Binary/CesiumMan.glb");
    let scene = load_scene(&path, &LoadOptions::default())
        .with_context(|| format!("refit bench asset (from --assets {})", assets.display()))?;
    let camera = CameraChoice::LookAt {
        eye: Vec3::new(0.0, 0.8, 2.6),
        target: Vec3::new(0.0, 0.75, 0.0),
        yfov: 45f32.to_radians(),
    };
    Ok((scene, camera))
}
