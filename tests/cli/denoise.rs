//! `raykin render --denoise` against the library's denoiser (tests/engine/denoise.rs tests the denoiser).

use crate::common::cornell::{self, EPS};
use crate::common::{gpu, rel_mse, shared_assets};

/// `raykin render --denoise svgf` writes the svgf-denoised image: the EXR equals `HeadlessApp::denoised_radiance` for the
/// same settings, and differs from the render without `--denoise`, which equals the radiance of an app that keeps no
/// denoiser inputs (its kernel stratifies the film position; the denoisers' does not).
#[test]
fn render_command_writes_the_denoised_image() {
    let dir = std::env::temp_dir().join(format!("raykin-denoise-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let run = |out: &std::path::Path, denoise: bool| {
        let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_raykin"));
        cmd.arg("render")
            .arg(shared_assets().join("CornellBox/CornellBox.glb"))
            .args([
                "--width", "16", "--height", "16", "--spp", "4", "--seed", "61",
            ])
            .args(["--env", "0,0,0", "--max-depth", "8", "--fov", "39.3077"])
            .args(["--look-from=-278,273,800", "--look-at=-278,273,0"])
            .arg("--out")
            .arg(out);
        if denoise {
            cmd.args(["--denoise", "svgf"]);
        }
        let status = cmd.status().expect("raykin runs");
        assert!(
            status.success(),
            "raykin render failed for {}",
            out.display()
        );
        out.to_path_buf()
    };
    let denoised_exr = run(&dir.join("denoised.exr"), true);
    let plain_exr = run(&dir.join("plain.exr"), false);
    let read = |p: &std::path::Path| raykin::image_io::read_exr(p).expect("EXR").2;
    let (from_cli, plain) = (read(&denoised_exr), read(&plain_exr));

    let (ctx, _gpu) = gpu();
    let mut app = cornell::app(ctx, true, 16, 61);
    app.accumulate(4, 16, |_| {});
    let expected = app.denoised_radiance();
    assert!(
        rel_mse(&from_cli, &expected, EPS) < 1e-10,
        "`--denoise` EXR differs from HeadlessApp::denoised_radiance"
    );
    let mut plain_app = cornell::app(app.ctx.clone(), true, 16, 61);
    plain_app.set_keep_denoiser_inputs(false);
    plain_app.accumulate(4, 16, |_| {});
    assert!(
        rel_mse(&plain, &plain_app.radiance(), EPS) < 1e-10,
        "the render without --denoise differs from HeadlessApp::radiance without the denoisers' inputs"
    );
    assert!(
        rel_mse(&from_cli, &plain, EPS) > 1e-4,
        "--denoise changed nothing"
    );

    let denoised_png = run(&dir.join("denoised.png"), true);
    let plain_png = run(&dir.join("plain.png"), false);
    assert_ne!(
        std::fs::read(denoised_png).unwrap(),
        std::fs::read(plain_png).unwrap(),
        "the tone-mapped PNG ignores --denoise"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
