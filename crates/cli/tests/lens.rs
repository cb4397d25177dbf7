//! Camera lenses (issue 25): the GPU's accumulated off-axis projections against the path
//! tracer's thin and thick lens, and the image-based model against the traced lens systems,
//! on `shadows` with direct light.

mod common;
use common::{lightlab, ok};
use lightlab_core::image::Image;
use std::path::Path;

fn relmse(a: &Path, b: &Path) -> f64 {
    relmse_images(&Image::read(a).unwrap(), &Image::read(b).unwrap())
}

/// Render `shadows` at `size` with `args`, into `out`.
fn run(size: &[&str], args: &[&str], out: &Path) {
    let mut a = vec!["render", "--scene", "shadows"];
    a.extend(size.iter().copied());
    a.extend(args.iter().copied());
    a.extend(["-o", out.to_str().unwrap()]);
    ok(&lightlab(&a));
}

const GPU: [&str; 6] = [
    "--technique",
    "phong-shadow-volumes",
    "--ambient",
    "none",
    "--ssaa",
    "2",
];

#[test]
fn the_gpu_thin_and_thick_lenses_match_the_traced_ones() {
    let tmp = tempfile::tempdir().unwrap();
    let size = ["--width", "128", "--height", "96"];
    let pinhole = tmp.path().join("pinhole.exr");
    run(&size, &GPU, &pinhole);
    for model in ["thin-lens", "thick-lens"] {
        let p = |n: &str| tmp.path().join(format!("{model}-{n}"));
        // The front pillars lie far before the plane of focus (the scene's centre): a 0.5 m
        // aperture blurs them over several pixels.
        let lens = [
            "--camera-model",
            model,
            "--aperture",
            "0.5",
            "--thickness",
            "0.3",
        ];
        let (reference, gpu) = (p("ref.exr"), p("gpu.exr"));
        let traced = ["--technique", "direct", "--spp", "512"];
        run(&size, &[&traced[..], &lens].concat(), &reference);
        run(
            &size,
            &[&GPU[..], &lens, &["--lens-samples", "16"]].concat(),
            &gpu,
        );
        let (e_lens, e_pinhole) = (relmse(&gpu, &reference), relmse(&pinhole, &reference));
        eprintln!(
            "relMSE against the traced {model}: GPU (16 samples) {e_lens:.2e}, GPU pinhole \
             {e_pinhole:.2e}"
        );
        // Each sample point is a full frame on lavapipe: 16 of them cost a quarter of the 64
        // this test used to take, and still measure well inside both bounds (see the closing
        // figures in docs/lenses.md).
        assert!(e_lens <= 0.01, "{model}: relMSE {e_lens}");
        assert!(
            e_lens < e_pinhole / 4.0,
            "{model}: the lens changes little: {e_lens} vs {e_pinhole}"
        );
    }
    // A lens that cannot form an image is refused before any work.
    let bad = tmp.path().join("bad.exr");
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
        bad.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(!bad.exists());
}

/// The image-based lens model (Heidrich §11.2) against the path tracer's traced lens, for
/// the shipped doublet and biconvex lens.
#[test]
fn the_image_based_model_matches_the_traced_lenses() {
    let tmp = tempfile::tempdir().unwrap();
    let size = ["--width", "96", "--height", "72"];
    for lens in ["doublet", "biconvex"] {
        let p = |n: &str| tmp.path().join(format!("{lens}-{n}"));
        let model = format!("lens:{lens}");
        let lens_args = ["--camera-model", model.as_str()];
        let traced = ["--technique", "direct", "--spp", "256"];
        run(&size, &[&traced[..], &lens_args].concat(), &p("ref.exr"));
        // 24 and 8 points: a third of the cost of the 64 and 10 this test used to take.
        for n in ["24", "8"] {
            let args = [&GPU[..], &lens_args, &["--lens-samples", n]].concat();
            run(&size, &args, &p(&format!("{n}.exr")));
        }
        let e24 = relmse(&p("24.exr"), &p("ref.exr"));
        let e8 = relmse(&p("8.exr"), &p("ref.exr"));
        eprintln!("{lens}: relMSE against the traced lens: 24 sample points {e24:.2e}, 8 {e8:.2e}");
        assert!(e24 <= 0.01, "{lens}: {e24}");
        assert!(
            e24 < 0.8 * e8,
            "{lens}: more sample points converge: {e24} vs {e8}"
        );
    }
    // A prescription that is not there names the shipped lenses.
    let bad = tmp.path().join("bad.exr");
    let o = lightlab(&[
        "render",
        "--scene",
        "shadows",
        "--technique",
        "direct",
        "--camera-model",
        "lens:no-such.lens",
        "-o",
        bad.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("doublet, biconvex, double-gauss"), "{err}");
}

/// A glTF camera that names its lens in `extras.lightlab.lens` renders as the same lens
/// named on the command line; the command line overrides the file.
#[test]
fn a_gltf_camera_names_its_lens() {
    let tmp = tempfile::tempdir().unwrap();
    let p = |n: &str| tmp.path().join(n);
    let gltf = p("shadows.gltf");
    ok(&lightlab(&[
        "export",
        "--scene",
        "shadows",
        "-o",
        gltf.to_str().unwrap(),
    ]));
    let text = std::fs::read_to_string(&gltf).unwrap();
    let named = r#""extras": {"lightlab": {"lens": {"model": "lens:doublet", "aperture": 0.004}}}, "type": "perspective""#;
    assert!(text.contains(r#""type": "perspective""#));
    std::fs::write(&gltf, text.replacen(r#""type": "perspective""#, named, 1)).unwrap();
    let size = ["--width", "48", "--height", "36"];
    let traced = ["--technique", "direct", "--spp", "16"];
    let render = |args: &[&str], out: &Path| {
        let mut a = vec!["render", "--scene", gltf.to_str().unwrap()];
        a.extend(size);
        a.extend(traced);
        a.extend(args.iter().copied());
        a.extend(["-o", out.to_str().unwrap()]);
        ok(&lightlab(&a));
    };
    render(&[], &p("file.exr"));
    let flags = ["--camera-model", "lens:doublet", "--aperture", "0.004"];
    render(&flags, &p("flags.exr"));
    render(&["--camera-model", "pinhole"], &p("pinhole.exr"));
    let read = |n: &str| Image::read(&p(n)).unwrap().data;
    assert_eq!(read("file.exr"), read("flags.exr"));
    assert_ne!(read("file.exr"), read("pinhole.exr"));
}

/// The viewer accumulates a lens's steps while the camera rests: once complete, its
/// screenshot is `render`'s image through the same lens (thin lens and a traced lens).
#[test]
fn the_viewer_shows_the_lens_once_its_steps_are_done() {
    let tmp = tempfile::tempdir().unwrap();
    let (shot, rendered) = (tmp.path().join("view.png"), tmp.path().join("render.png"));
    let lenses: [&[&str]; 2] = [
        &[
            "--camera-model",
            "thin-lens",
            "--aperture",
            "0.5",
            "--lens-samples",
            "4",
        ],
        &["--camera-model", "lens:biconvex", "--lens-samples", "3"],
    ];
    for lens in lenses {
        let size = ["--width", "96", "--height", "72"];
        let technique = ["--scene", "shadows", "--technique", "phong-shadow-volumes"];
        let mut a = vec![
            "view",
            "--frames",
            "6",
            "--screenshot",
            shot.to_str().unwrap(),
        ];
        a.extend(technique.iter().chain(&size).chain(lens));
        let o = lightlab(&a);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let mut a = vec!["render", "-o", rendered.to_str().unwrap()];
        a.extend(technique.iter().chain(&size).chain(lens));
        ok(&lightlab(&a));
        let (a, b) = (Image::read(&shot).unwrap(), Image::read(&rendered).unwrap());
        let e = relmse_images(&a, &b);
        assert!(e < 1e-3, "{lens:?}: {e}");
    }
}

fn relmse_images(a: &Image, b: &Image) -> f64 {
    let (mut e, mut n) = (0.0f64, 0.0f64);
    for (x, y) in a.data.iter().zip(&b.data) {
        e += (*x - *y).length_squared() as f64;
        n += y.length_squared() as f64;
    }
    e / n
}
