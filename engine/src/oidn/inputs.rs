//! OIDN's inputs from the view's accumulation, and how each pixel's mean reaches the display through it
//! ([`PixelSplit`]), with the first-hit albedo and normal as
//! OIDN documents its auxiliary images (anti-aliased like the colour, albedo in [0, 1], normals averaged but
//! not renormalised, so an edge pixel's normal is the mean of its sub-pixel normals). Through mirror-like metal
//! the path kernel records the surface the mirror shows instead (shaders/integrator/path.wgsl).

use crate::gpu::GpuContext;
use crate::render::ViewTargets;
use crate::render::passes::denoiser_planes::DenoiserSources;

/// How a pixel's mean reaches the display through the denoiser, by where its samples' first hits were (the
/// GPU path's `pixel_split` in render/passes/denoiser_planes/split.wgsl is the same rule).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PixelSplit {
    /// Every sample met a surface: the denoiser gets the scattered radiance; what reached the camera
    /// unscattered (emitters seen directly, exact at any sample count) is added back afterwards, as the svgf
    /// denoiser does (given to OIDN, a light's radiance came back distorted: the Cornell box's linear relMSE
    /// gain at 4 spp 136x split, 74x whole).
    Scattered,
    /// Some samples met a surface, or none did beside a pixel where some did: an outline against the
    /// environment. The denoiser gets the whole mean, so the environment's coverage noise is denoised with the
    /// rest (split off, it passed through undenoised: FlightHelmet's relMSE gain at 4 spp 2.4x split, 3.2x
    /// whole; docs/BENCHMARKS.md).
    Whole,
    /// No sample met a surface here nor in the 8 pixels around: the environment seen directly, exact. The
    /// denoiser still gets it (so its background is continuous) but the display shows the mean: given back by
    /// the network it carried a low-frequency residue (FlightHelmet at 64 spp, H200: FLIP 0.0032 noisy,
    /// 0.0131 after OIDN high).
    Kept,
}

impl PixelSplit {
    /// The split of every pixel of a `width` x `height` image from its sample count (`accum`'s w) and
    /// first-surface hit count (`normal_hits`' w).
    pub fn of_image(
        width: u32,
        height: u32,
        accum: &[[f32; 4]],
        normal_hits: &[[f32; 4]],
    ) -> Vec<PixelSplit> {
        use rayon::prelude::*;
        let (w, h) = (width as usize, height as usize);
        let met_surface = |i: usize| normal_hits.get(i).is_some_and(|p| p[3] > 0.0);
        (0..accum.len().min(normal_hits.len()).min(w * h))
            .into_par_iter()
            .map(|i| {
                let (hits, samples) = (normal_hits[i][3], accum[i][3]);
                if hits > 0.0 && hits >= samples {
                    return PixelSplit::Scattered;
                }
                let (x, y) = (i % w, i / w);
                let near_surface = (y.saturating_sub(1)..=(y + 1).min(h - 1)).any(|ny| {
                    (x.saturating_sub(1)..=(x + 1).min(w - 1)).any(|nx| met_surface(ny * w + nx))
                });
                if near_surface {
                    PixelSplit::Whole
                } else {
                    PixelSplit::Kept
                }
            })
            .collect()
    }
}

/// Host images for [`super::Oidn::denoise`], row-major from the top-left.
#[derive(Clone, Debug, Default)]
pub struct OidnInputs {
    pub width: u32,
    pub height: u32,
    /// The radiance to denoise: the mean, less `unscattered` where it is split off.
    pub color: Vec<[f32; 3]>,
    /// Mean radiance added back to OIDN's output, not denoised: the unscattered part of [`PixelSplit::Scattered`]
    /// pixels; 0 elsewhere.
    pub unscattered: Vec<[f32; 3]>,
    /// [`PixelSplit::Kept`] pixels, shown as their mean.
    pub kept: Vec<bool>,
    pub albedo: Vec<[f32; 3]>,
    pub normal: Vec<[f32; 3]>,
    /// Samples per pixel behind these images.
    pub samples: u32,
}

impl OidnInputs {
    /// From the accumulation sums, per pixel: radiance + sample count, first-hit albedo + depth (summed over
    /// samples that hit), first-hit normal + hit count, and the denoiser moments (unscattered radiance +
    /// a luminance moment).
    ///
    /// Each pixel's mean goes to OIDN as its [`PixelSplit`] says.
    ///
    /// Samples that left the scene count as albedo 0 and normal 0. Measured against albedo 1 and against the
    /// environment's radiance clamped to 1 (the rule for emitters some renderers use), OIDN high at 4 spp,
    /// 64x64, relMSE against Mitsuba or 256 spp: Cornell box (black environment) 6.55e-2 / 6.41e-2, but a
    /// converged input moved 6x less away from the light (8.0e-5 / 5.0e-4); sky-lit checker plane
    /// 7.02e-3 / 6.97e-3 / 7.03e-3; sky-lit FlightHelmet 7.24e-3 / 8.00e-3 / 7.74e-3.
    pub fn from_sums(
        width: u32,
        height: u32,
        accum: &[[f32; 4]],
        albedo_depth: &[[f32; 4]],
        normal_hits: &[[f32; 4]],
        moments: &[[f32; 4]],
    ) -> Self {
        // Means in parallel: at 1440p these are 11 million pixels' divisions over 180 MB of mapped memory.
        use rayon::prelude::*;
        let means = |plane: &[[f32; 4]]| -> Vec<[f32; 3]> {
            plane
                .par_iter()
                .zip(accum)
                .map(|(p, a)| {
                    let n = a[3].max(1.0);
                    [p[0] / n, p[1] / n, p[2] / n]
                })
                .collect()
        };
        let splits = PixelSplit::of_image(width, height, accum, normal_hits);
        let (color, unscattered): (Vec<[f32; 3]>, Vec<[f32; 3]>) = means(accum)
            .into_par_iter()
            .zip(means(moments))
            .zip(&splits)
            .map(|((m, u), split)| match split {
                PixelSplit::Scattered => ([0, 1, 2].map(|c| (m[c] - u[c]).max(0.0)), u),
                PixelSplit::Whole | PixelSplit::Kept => (m, [0.0; 3]),
            })
            .unzip();
        Self {
            width,
            height,
            color,
            unscattered,
            kept: splits.iter().map(|s| *s == PixelSplit::Kept).collect(),
            albedo: means(albedo_depth),
            normal: means(normal_hits),
            samples: accum.first().map_or(0, |a| a[3] as u32),
        }
    }

    pub fn images(&self) -> super::Images<'_> {
        super::Images {
            width: self.width,
            height: self.height,
            color: &self.color,
            albedo: Some(&self.albedo),
            normal: Some(&self.normal),
            unscattered: Some(&self.unscattered),
            kept: Some(&self.kept),
        }
    }
}

/// Reads the view's current accumulation back (blocking) as OIDN inputs: its three planes in one staging copy,
/// one submission and one wait, turned into means straight from the mapped memory. Also returns the seconds
/// that took (the GPU-to-host copy and the means).
pub fn read_inputs(ctx: &GpuContext, view: &ViewTargets) -> (OidnInputs, f64) {
    read_sources(ctx, &view.denoiser_sources())
}

/// [`read_inputs`] from the accumulation's buffers (what another thread holds).
pub fn read_sources(ctx: &GpuContext, sources: &DenoiserSources) -> (OidnInputs, f64) {
    let start = std::time::Instant::now();
    let planes = [
        &sources.accum,
        &sources.albedo_depth,
        &sources.normal_hits,
        &sources.moments,
    ];
    let inputs = ctx.read_buffers_with(&planes, |bytes| {
        inputs_from_planes(sources.width, sources.height, bytes)
    });
    (inputs, start.elapsed().as_secs_f64())
}

/// OIDN inputs from the accumulation, albedo + depth, normal + hits and moments planes, back to back in
/// `bytes`.
pub(crate) fn inputs_from_planes(width: u32, height: u32, bytes: &[u8]) -> OidnInputs {
    let planes: Vec<[f32; 4]>;
    // Mapped GPU memory is aligned; a copy is made only for bytes that are not.
    let planes: &[[f32; 4]] = match bytemuck::try_cast_slice(bytes) {
        Ok(p) => p,
        Err(_) => {
            planes = bytemuck::pod_collect_to_vec(bytes);
            &planes
        }
    };
    let n = planes.len() / 4;
    OidnInputs::from_sums(
        width,
        height,
        &planes[..n],
        &planes[n..2 * n],
        &planes[2 * n..3 * n],
        &planes[3 * n..],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sums_become_means_with_misses_counting_zero() {
        // Pixel 0: 4 samples, all hits on albedo 0.5, normal +z, with an emitter seen directly (unscattered 4).
        // Pixel 1: 4 samples, 1 hit (albedo 0.2, normal +x), 3 misses that saw sky radiance summing to 1.
        let accum = [[8.0, 8.0, 12.0, 4.0], [2.0, 2.0, 2.0, 4.0]];
        let albedo = [[2.0, 2.0, 2.0, 7.0], [0.2, 0.2, 0.2, 1.0]];
        let normal = [[0.0, 0.0, 4.0, 4.0], [1.0, 0.0, 0.0, 1.0]];
        // The moments' w is a luminance moment, unused here.
        let moments = [[4.0, 0.0, 0.0, 9.0], [1.0, 1.0, 1.0, 0.0]];
        let inputs = OidnInputs::from_sums(2, 1, &accum, &albedo, &normal, &moments);
        // Pixel 0 is split (the emitter's mean set apart); the outline pixel goes to OIDN whole.
        assert_eq!(inputs.color, vec![[1.0, 2.0, 3.0], [0.5, 0.5, 0.5]]);
        assert_eq!(inputs.unscattered, vec![[1.0, 0.0, 0.0], [0.0; 3]]);
        assert_eq!(inputs.kept, vec![false, false]);
        assert_eq!(inputs.albedo[0], [0.5; 3]);
        assert_eq!(inputs.albedo[1], [0.05; 3]);
        // The edge pixel's normal keeps its sub-pixel coverage (length 1/4), as OIDN asks.
        assert_eq!(inputs.normal, vec![[0.0, 0.0, 1.0], [0.25, 0.0, 0.0]]);
        assert_eq!(inputs.samples, 4);
        assert!(inputs.images().validate().is_ok());
    }

    #[test]
    fn only_the_environment_away_from_any_surface_is_kept() {
        // 5x3 pixels, 2 samples each; the surface covers column 0 (both samples) and pixel (1, 1) (one sample).
        let (w, h) = (5u32, 3u32);
        let hits = |x: u32, y: u32| match (x, y) {
            (0, _) => 2.0,
            (1, 1) => 1.0,
            _ => 0.0,
        };
        let accum: Vec<[f32; 4]> = (0..w * h).map(|_| [2.0, 2.0, 2.0, 2.0]).collect();
        let normal_hits: Vec<[f32; 4]> = (0..w * h)
            .map(|i| [0.0, 0.0, hits(i % w, i / w), hits(i % w, i / w)])
            .collect();
        let splits = PixelSplit::of_image(w, h, &accum, &normal_hits);
        let row = |y: usize| splits[y * w as usize..(y + 1) * w as usize].to_vec();
        use PixelSplit::*;
        // Columns 1-2 touch a pixel some sample's surface met; columns 3-4 see only the environment.
        assert_eq!(row(0), vec![Scattered, Whole, Whole, Kept, Kept]);
        assert_eq!(row(1), vec![Scattered, Whole, Whole, Kept, Kept]);
        assert_eq!(row(2), vec![Scattered, Whole, Whole, Kept, Kept]);
        let moments = vec![[0.5, 0.5, 0.5, 0.0]; (w * h) as usize];
        let inputs = OidnInputs::from_sums(w, h, &accum, &accum, &normal_hits, &moments);
        // Kept pixels still reach OIDN with their whole mean (a continuous background) and nothing added back.
        assert_eq!(inputs.color[4], [1.0; 3]);
        assert_eq!(inputs.unscattered[4], [0.0; 3]);
        assert!(inputs.kept[4] && !inputs.kept[2]);
        assert_eq!(inputs.color[0], [0.75; 3]);
        assert_eq!(inputs.unscattered[0], [0.25; 3]);
    }

    #[test]
    fn planes_back_to_back_read_as_from_sums_aligned_or_not() {
        let accum = [[4.0, 8.0, 12.0, 4.0], [2.0, 2.0, 2.0, 4.0]];
        let albedo = [[2.0, 2.0, 2.0, 7.0], [0.2, 0.2, 0.2, 1.0]];
        let normal = [[0.0, 0.0, 4.0, 4.0], [1.0, 0.0, 0.0, 1.0]];
        let moments = [[0.5, 0.0, 0.0, 1.0], [0.0, 0.2, 0.0, 1.0]];
        let expected = OidnInputs::from_sums(2, 1, &accum, &albedo, &normal, &moments);
        let planes: Vec<[f32; 4]> = [accum, albedo, normal, moments].concat();
        let bytes: &[u8] = bytemuck::cast_slice(&planes);
        let got = inputs_from_planes(2, 1, bytes);
        assert_eq!(
            (got.color, got.unscattered, got.albedo, got.normal),
            (
                expected.color.clone(),
                expected.unscattered.clone(),
                expected.albedo.clone(),
                expected.normal.clone()
            )
        );
        // The same bytes one byte into a buffer: not aligned for f32, read through a copy.
        let mut shifted = vec![0u8; bytes.len() + 1];
        shifted[1..].copy_from_slice(bytes);
        let got = inputs_from_planes(2, 1, &shifted[1..]);
        assert_eq!(
            (got.color, got.albedo, got.normal, got.samples),
            (expected.color, expected.albedo, expected.normal, 4)
        );
    }

    #[test]
    fn an_empty_accumulation_reads_as_black() {
        let zero = [[0.0f32; 4]];
        let inputs = OidnInputs::from_sums(1, 1, &zero, &zero, &zero, &zero);
        assert_eq!(inputs.color, vec![[0.0; 3]]);
        assert_eq!(inputs.normal, vec![[0.0; 3]]);
        assert_eq!(inputs.samples, 0);
    }
}
