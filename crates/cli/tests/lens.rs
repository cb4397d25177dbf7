//! Camera lenses (issue 25): the GPU's accumulated off-axis projections against the path
//! tracer's thin lens, on `shadows` with direct light.

mod common;
use common::{lightlab, ok};
use lightlab_core::image::Image;
use std::path::Path;

fn relmse(a: &Path, b: &Path) -> f64 {
    let (a, b) = (Image::read(a).unwrap(), Image::read(b).unwrap());
    let (mut e, mut n) = (0.0f64, 0.0f64);
    for (x, y) in a.data.iter().zip(&b.data) {
        e += (*x - *y).length_squared() as f64;
        n += y.length_squared() as f64;
    }
    e / n
}

#[test]
fn the_gpu_thin_lens_matches_the_traced_one() {
    let tmp = tempfile::tempdir().unwrap();
    let p = |n: &str| tmp.path().join(n);
    let size = ["--width", "128", "--height", "96"];
    // The front pillars lie far before the plane of focus (the scene's centre): a 0.5 m
    // aperture blurs them over several pixels.
    let lens = ["--camera-model", "thin-lens", "--aperture", "0.5"];
    let run = |args: &[&str], out: &Path| {
        let mut a = vec!["render", "--scene", "shadows"];
        a.extend(size);
        a.extend(args);
        a.extend(["-o", out.to_str().unwrap()]);
        ok(&lightlab(&a));
    };
    let (reference, thin, pinhole) = (p("ref.exr"), p("thin.exr"), p("pinhole.exr"));
    run(
        &[&["--technique", "direct", "--spp", "512"][..], &lens].concat(),
        &reference,
    );
    let gpu = [
        "--technique",
        "phong-shadow-volumes",
        "--ambient",
        "none",
        "--ssaa",
        "2",
    ];
    run(
        &[&gpu[..], &lens, &["--lens-samples", "64"]].concat(),
        &thin,
    );
    run(&gpu, &pinhole);
    let (e_thin, e_pinhole) = (relmse(&thin, &reference), relmse(&pinhole, &reference));
    eprintln!(
        "relMSE against the traced thin lens: GPU thin lens (64 samples) {e_thin:.2e}, GPU \
         pinhole {e_pinhole:.2e}"
    );
    assert!(e_thin <= 0.01, "thin lens: relMSE {e_thin}");
    assert!(
        e_thin < e_pinhole / 3.0,
        "the lens changes little: {e_thin} vs {e_pinhole}"
    );
    // A lens that cannot form an image is refused before any work.
    let o = lightlab(&[
        "render",
        "--scene",
        "shadows",
        "--technique",
        "direct",
        "--camera-model",
        "thin-lens",
        "--focus-distance",
        "-1",
        "-o",
        p("bad.exr").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(!p("bad.exr").exists());
}
