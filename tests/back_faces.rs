//! The back-face probe: how much of the camera's view lands on the back of one-sided surfaces (black in
//! pass two), as `radray info` reports it and `render` warns about it.

mod common;

use common::{radray, scene, z_quad};
use radray::accel::Accel;
use radray::mesh::Mesh;
use radray::scene::{Material, SceneDescription};
use radray::trace::back_faces::{probe_scene, BackFaceShare, PROBE_RAYS_ACROSS};

fn grey() -> Material {
    Material::diffuse("grey", glam::Vec3::splat(0.5))
}

fn share_of(scene: &SceneDescription) -> BackFaceShare {
    let mesh = Mesh::build(scene, 10.0);
    let accel = Accel::build(&mesh.positions, &mesh.triangles);
    probe_scene(scene, &mesh, &accel)
}

#[test]
fn a_one_sided_wall_seen_from_behind_is_all_back_faces_and_two_sided_is_none() {
    // The default camera looks from z = 5 towards −z; a quad facing −z is seen from behind.
    let behind = scene(vec![grey()], vec![z_quad(0.0, 10.0, false, 0, false)]);
    let share = share_of(&behind);
    let rays = (PROBE_RAYS_ACROSS * PROBE_RAYS_ACROSS) as u64;
    assert_eq!(share, BackFaceShare { rays, hits: rays, back_hits: rays });
    assert!(share.warning().expect("100% warns").contains("two_sided = true"));

    let two_sided = scene(vec![grey()], vec![z_quad(0.0, 10.0, false, 0, true)]);
    assert_eq!(share_of(&two_sided).back_hits, 0);
    let facing = scene(vec![grey()], vec![z_quad(0.0, 10.0, true, 0, false)]);
    assert_eq!(share_of(&facing).back_hits, 0);
}

#[test]
fn glass_seen_from_behind_is_not_a_black_back_face() {
    let glass = scene(vec![common::glass("glass")], vec![z_quad(0.0, 10.0, false, 0, false)]);
    assert_eq!(share_of(&glass).back_hits, 0, "dielectrics refract on both sides");
}

#[test]
fn share_counts_the_probe_cells_whose_ray_meets_a_reversed_square() {
    // A front-facing wall fills the view (half-size 2 at distance 5 > tan 20°); a reversed square of
    // half-size 0.5 at z = 1 (distance 4) covers |s| < 0.125 / tan 20° = 0.3434 of the film's half-width.
    // Probe cell i of 64 has its centre at s = (i + 0.5)/32 − 1, inside for i = 21..=42: 22 cells a side.
    let surfaces = vec![z_quad(0.0, 2.0, true, 0, false), z_quad(1.0, 0.5, false, 0, false)];
    let share = share_of(&scene(vec![grey()], surfaces));
    assert_eq!((share.rays, share.hits, share.back_hits), (4096, 4096, 22 * 22));
    assert!(share.share() > 0.05 && share.warning().is_some(), "11.8% is above the 5% threshold");
}

/// A scene file: one grey wall facing away from the camera, with `two_sided` as given.
fn wall_scene(dir: &std::path::Path, two_sided: bool) -> String {
    let text = format!(
        "[camera]\neye = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\nup = [0.0, 1.0, 0.0]\nvfov_deg = 40.0\n\n\
         [image]\nwidth = 16\nheight = 12\nsamples_per_pixel = 1\n\n\
         [[material]]\nname = \"grey\"\nkd = [0.5, 0.5, 0.5]\n\n\
         [[quad]]\ncorners = [[-9, -9, 0], [-9, 9, 0], [9, 9, 0], [9, -9, 0]]\nmaterial = \"grey\"\ntwo_sided = {two_sided}\n"
    );
    let path = dir.join(format!("wall_{two_sided}.toml"));
    std::fs::write(&path, text).unwrap();
    path.display().to_string()
}

#[test]
fn info_reports_the_share_and_suggests_two_sided_and_render_warns() {
    let dir = tempfile::tempdir().unwrap();
    let behind = wall_scene(dir.path(), false);
    let out = radray(&["info", &behind, "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["back_faces"]["back_hits"], v["back_faces"]["hits"]);
    assert!(v["back_faces"]["hits"].as_u64().unwrap() > 0);
    let text = String::from_utf8_lossy(&radray(&["info", &behind]).stdout).into_owned();
    assert!(text.contains("100.0% of primary hits") && text.contains("`two_sided = true`"), "{text}");

    let png = dir.path().join("wall.png");
    let render = |scene: &str| radray(&["render", scene, "-o", png.to_str().unwrap()]);
    let out = render(&behind);
    assert!(out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(stderr.contains("warning: 100.0% of the camera's primary hits"), "{stderr}");

    let fixed = wall_scene(dir.path(), true);
    let out = render(&fixed);
    assert!(out.status.success());
    assert!(!String::from_utf8_lossy(&out.stderr).contains("primary hits"));
    let text = String::from_utf8_lossy(&radray(&["info", &fixed]).stdout).into_owned();
    assert!(text.contains("back faces      0.0%") && !text.contains("suggestion"), "{text}");
}
