//! Layered EXR (`render --layers`): the compositor channel names, the parts adding up to the beauty,
//! the beauty and radiosity layers equal to the plain renders, and the first-hit layers.

mod common;

use common::radray;
use radray::output::read_exr_channels;
use std::collections::HashMap;
use std::path::Path;

fn scene(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name).display().to_string()
}

#[test]
fn layers_add_up_to_the_beauty_under_compositor_names() {
    let dir = tempfile::tempdir().unwrap();
    let (layers, plain) = (dir.path().join("layers.exr"), dir.path().join("plain.exr"));
    // A mirror, a glass ball and a lamp in view, with per-pixel direct light: every part is non-zero.
    let small = ["--width", "24", "--height", "18", "--spp", "2", "--quality", "preview", "--direct", "pixel"];
    let s = scene("primitives.toml");
    let mut args = vec!["render", s.as_str(), "-o", plain.to_str().unwrap(), "--mode", "both"];
    args.extend(["--layers", layers.to_str().unwrap()]);
    args.extend(small);
    let out = radray(&args);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));

    let channels: HashMap<String, Vec<f32>> = read_exr_channels(&layers).unwrap().into_iter().collect();
    let mut names: Vec<&str> = channels.keys().map(String::as_str).collect();
    names.sort();
    let mut expected = vec!["R", "G", "B", "depth.Z"];
    let rgb_layers = ["direct", "indirect", "specular", "emitted", "radiosity", "albedo", "normal"];
    let rgb_names: Vec<String> = rgb_layers.iter().flat_map(|l| ["R", "G", "B"].map(|c| format!("{l}.{c}"))).collect();
    expected.extend(rgb_names.iter().map(String::as_str));
    expected.sort();
    assert_eq!(names, expected);

    // The beauty is the plain final render, bit for bit; the radiosity layer is `--mode radiosity`.
    let final_image = radray::output::read_image(&dir.path().join("plain.final.exr")).unwrap();
    let radiosity_image = radray::output::read_image(&dir.path().join("plain.radiosity.exr")).unwrap();
    for (c, name) in ["R", "G", "B"].iter().enumerate() {
        let beauty = &channels[*name];
        assert!(beauty.iter().zip(&final_image.pixels).all(|(b, p)| b.to_bits() == p[c].to_bits()));
        let radiosity = &channels[&format!("radiosity.{name}")];
        assert!(radiosity.iter().zip(&radiosity_image.pixels).all(|(r, p)| r.to_bits() == p[c].to_bits()));
        // direct + indirect + specular + emitted = beauty: exact in real numbers, so only f32 rounding
        // of four terms and of the film's weighted mean separates them (1e-4 relative, 1e-7 absolute
        // below the smallest radiance shown).
        for (i, b) in beauty.iter().enumerate() {
            let sum: f32 =
                ["direct", "indirect", "specular", "emitted"].iter().map(|l| channels[&format!("{l}.{name}")][i]).sum();
            assert!((sum - b).abs() <= 1e-4 * b.abs() + 1e-7, "pixel {i} {name}: parts {sum} vs beauty {b}");
        }
    }
    let total = |layer: &str| -> f32 {
        ["R", "G", "B"].iter().map(|c| channels[&format!("{layer}.{c}")].iter().sum::<f32>()).sum()
    };
    for layer in ["direct", "indirect", "specular", "emitted", "albedo"] {
        assert!(total(layer) > 0.0, "{layer} is not empty");
    }
    // Depth: distance to the first hit, inside the room (a few metres); normals of unit length.
    let depth = &channels["depth.Z"];
    assert!(depth.iter().all(|d| d.is_finite() && *d > 0.0 && *d < 20.0), "{depth:?}");
    let (nx, ny, nz) = (&channels["normal.R"], &channels["normal.G"], &channels["normal.B"]);
    let unit =
        (0..depth.len()).filter(|&i| ((nx[i] * nx[i] + ny[i] * ny[i] + nz[i] * nz[i]).sqrt() - 1.0).abs() < 1e-3);
    // Pixels on an edge average two normals (shorter than 1); most pixels see one surface.
    assert!(unit.count() > depth.len() / 2);
}

#[test]
fn layers_must_be_exr_in_an_existing_directory() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("a.png");
    for bad in [dir.path().join("l.png"), dir.path().join("missing").join("l.exr")] {
        let o = radray(&[
            "render",
            &scene("cornell_box.toml"),
            "-o",
            out.to_str().unwrap(),
            "--layers",
            bad.to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(2));
        assert!(String::from_utf8_lossy(&o.stderr).contains(bad.to_str().unwrap()));
    }
    assert!(!out.exists(), "refused before any work");
}
