//! OIDN's inputs from the view's accumulation: mean scattered radiance (the unscattered part is exact and added
//! back after denoising), and the first-hit albedo and normal as
//! OIDN documents its auxiliary images (anti-aliased like the colour, albedo in [0, 1], normals averaged but
//! not renormalised, so an edge pixel's normal is the mean of its sub-pixel normals). Through mirror-like metal
//! the path kernel records the surface the mirror shows instead (shaders/integrator/path.wgsl).

use crate::gpu::GpuContext;
use crate::render::ViewTargets;
use crate::render::passes::denoiser_planes::DenoiserSources;

/// Host images for [`super::Oidn::denoise`], row-major from the top-left.
#[derive(Clone, Debug, Default)]
pub struct OidnInputs {
    pub width: u32,
    pub height: u32,
    /// The radiance to denoise: the mean minus `unscattered`.
    pub color: Vec<[f32; 3]>,
    /// Mean radiance that reached the camera without scattering (emitters and the environment seen directly):
    /// exact, so it is not denoised but added back to OIDN's output, as the svgf denoiser does.
    pub unscattered: Vec<[f32; 3]>,
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
    /// OIDN gets the scattered radiance only (the mean minus the unscattered part, at least 0): left in, the
    /// sky and the lights seen directly, exact at any sample count, came back with the network's
    /// low-frequency residue (FlightHelmet at 64 spp, H200: FLIP 0.0032 noisy, 0.0131 after OIDN high, 0.0029
    /// with the split; docs/BENCHMARKS.md). Setting apart only the pixels no sample's surface met (the sky)
    /// was worse: OIDN then saw a black background beside outlines that hold the sky's radiance.
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
        let mean = means(accum);
        let unscattered = means(moments);
        let color = mean
            .par_iter()
            .zip(&unscattered)
            .map(|(m, u)| [0, 1, 2].map(|c| (m[c] - u[c]).max(0.0)))
            .collect();
        Self {
            width,
            height,
            color,
            unscattered,
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
        // Pixel 0: 4 samples, all hits on albedo 0.5, normal +z. Pixel 1: 4 samples, 1 hit (albedo 0.2, normal
        // +x), 3 misses.
        let accum = [[4.0, 8.0, 12.0, 4.0], [2.0, 2.0, 2.0, 4.0]];
        let albedo = [[2.0, 2.0, 2.0, 7.0], [0.2, 0.2, 0.2, 1.0]];
        let normal = [[0.0, 0.0, 4.0, 4.0], [1.0, 0.0, 0.0, 1.0]];
        // Pixel 1's three misses saw sky radiance summing to 1 (the moments' w is a luminance moment, unused
        // here).
        let moments = [[0.0, 0.0, 0.0, 9.0], [1.0, 1.0, 1.0, 0.0]];
        let inputs = OidnInputs::from_sums(2, 1, &accum, &albedo, &normal, &moments);
        // OIDN gets the scattered part; the unscattered mean is kept apart.
        assert_eq!(inputs.color, vec![[1.0, 2.0, 3.0], [0.25, 0.25, 0.25]]);
        assert_eq!(inputs.unscattered, vec![[0.0; 3], [0.25, 0.25, 0.25]]);
        assert_eq!(inputs.albedo[0], [0.5; 3]);
        assert_eq!(inputs.albedo[1], [0.05; 3]);
        // The edge pixel's normal keeps its sub-pixel coverage (length 1/4), as OIDN asks.
        assert_eq!(inputs.normal, vec![[0.0, 0.0, 1.0], [0.25, 0.0, 0.0]]);
        assert_eq!(inputs.samples, 4);
        assert!(inputs.images().validate().is_ok());
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
