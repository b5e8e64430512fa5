//! MTL files as exporters write them, and textures: what each statement becomes in a `Material`,
//! which inputs are clamped or refused, and that a texture's element mean albedo is its exact average.

use approx::assert_relative_eq;
use glam::{Vec2, Vec3, Vec4};
use radray::material::mtl::{self, MtlLibrary};
use radray::material::texture::srgb_to_linear;
use radray::material::{ColorEncoding, MaterialMaps, Texture, TextureCache, ALBEDO_CEILING};
use radray::scene::{self, Material};
use std::path::Path;

fn parse(text: &str) -> MtlLibrary {
    mtl::parse(Path::new("/scenes/box/scene.mtl"), text).expect("MTL parses")
}

fn material<'a>(lib: &'a MtlLibrary, name: &str) -> &'a Material {
    lib.materials.iter().find(|m| m.name == name).unwrap_or_else(|| panic!("no material {name}"))
}

/// A scene in a temporary folder: one textured quad (uv over the unit square) with material `wall`,
/// a lamp quad, and the given MTL text.
fn load_scene(
    mtl_text: &str,
    extra: &[(&str, &[u8])],
) -> (tempfile::TempDir, Result<scene::SceneDescription, scene::SceneError>) {
    let dir = tempfile::tempdir().expect("temp dir");
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
usemtl wall\nf 1/1 2/2 3/3 4/4\nusemtl lamp\nf 1 5 6 2\n";
    std::fs::write(dir.path().join("m.obj"), obj).expect("write OBJ");
    std::fs::write(dir.path().join("m.mtl"), format!("newmtl lamp\nKe 1 1 1\n\n{mtl_text}")).expect("write MTL");
    for (name, bytes) in extra {
        std::fs::write(dir.path().join(name), bytes).expect("write file");
    }
    let path = dir.path().join("scene.toml");
    std::fs::write(&path, "[[mesh]]\nobj = \"m.obj\"\n").expect("write scene");
    let result = scene::load(&path);
    (dir, result)
}

/// Values of order 1 computed in f32 through a few operations: 1e-6 is ~10 ulps.
fn assert_close(a: Vec3, b: Vec3) {
    assert!(a.abs_diff_eq(b, 1e-6), "{a} vs {b}");
}

fn png_bytes(width: u32, height: u32, grey: &[u8]) -> Vec<u8> {
    let image = image::GrayImage::from_raw(width, height, grey.to_vec()).expect("size matches");
    let mut bytes = Vec::new();
    image.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png).expect("encode PNG");
    bytes
}

// ---------------------------------------------------------------------------------------------------
// illum models

#[test]
fn illum_0_1_2_keep_ks_as_mirror_reflectance_and_ns_as_highlight() {
    let lib = parse(
        "newmtl a\nillum 1\nKd 0.5 0.5 0.5\nKs 0.2 0.2 0.2\nnewmtl b\nillum 2\nKd 0.4 0.4 0.4\nKs 0.3 0.3 0.3\nNs 40\n",
    );
    let (a, b) = (material(&lib, "a"), material(&lib, "b"));
    assert_eq!((a.specular_reflectance, a.transmittance, a.illum), (Vec3::splat(0.2), 0.0, Some(1)));
    assert_eq!((b.specular_reflectance, b.phong_exponent), (Vec3::splat(0.3), Some(40.0)));
    assert!(!b.is_dielectric());
}

#[test]
fn illum_3_5_8_are_mirrors_of_reflectance_ks() {
    let lib = parse("newmtl m3\nillum 3\nKd 0 0 0\nKs 0.9 0.9 0.9\nnewmtl m5\nillum 5\nKd 0 0 0\nKs 0.95 0.95 0.95\nNs 1000\nnewmtl m8\nillum 8\n");
    assert_eq!(material(&lib, "m3").specular_reflectance, Vec3::splat(0.9));
    assert_eq!(material(&lib, "m5").specular_reflectance, Vec3::splat(0.95));
    // Without Ks a reflection model is a perfect mirror.
    assert_eq!(material(&lib, "m8").specular_reflectance, Vec3::ONE);
    for m in &lib.materials {
        assert!(m.is_specular() && !m.is_dielectric(), "{}", m.name);
    }
}

#[test]
fn illum_4_6_7_9_are_clear_dielectrics_with_fresnel_from_ni() {
    for model in [4, 6, 7, 9] {
        let lib = parse(&format!("newmtl glass\nillum {model}\nKd 0 0 0\nNi 1.7\n"));
        let g = material(&lib, "glass");
        assert!(g.is_dielectric(), "illum {model}");
        assert_eq!((g.transmittance, g.ior, g.specular_reflectance), (1.0, 1.7, Vec3::ONE), "illum {model}");
    }
    // No Ni: ordinary glass.
    assert_eq!(material(&parse("newmtl g\nillum 7\n"), "g").ior, mtl::DEFAULT_GLASS_IOR);
}

#[test]
fn mcguire_sphere_and_water_are_clear_glass_and_water_and_the_left_sphere_a_mirror() {
    // As in CornellBox-Sphere.mtl and CornellBox-Water.mtl: CRLF, spaces and tabs, illum 7 with Tf.
    let text = "newmtl leftSphere\r\n    Kd 0.01 0.01 0.01\r\n    Ks 0.95 0.95 0.95\r\n    Ns 1000\r\n    illum 5\r\n\r\n\
newmtl rightSphere\r\n    Kd 0.01 0.01 0.01\r\n    Ks 0.30 0.30 0.30\r\n    Tf 0.10 0.10 0.10\r\n    Ns 200\r\n    Ni 2.5\r\n    illum 7\r\n\
newmtl water\r\n\tKd 0.01 0.01 0.01\r\n\tKs 0.30 0.30 0.30\r\n\tTf 0.10 0.10 0.10\r\n\tNs 200\r\n\tNi 1.33\r\n\tillum 7\r\n";
    let lib = parse(text);
    let mirror = material(&lib, "leftSphere");
    assert_eq!(mirror.specular_reflectance, Vec3::splat(0.95));
    assert!(!mirror.is_dielectric());
    for (name, ior) in [("rightSphere", 2.5), ("water", 1.33)] {
        let m = material(&lib, name);
        // Tf 0.1 in a transparent model is read as G3D reads it: 90 % transmitted, white filter.
        assert_relative_eq!(m.transmittance, 0.9, max_relative = 1e-6);
        assert_eq!(m.transmission_filter, Vec3::ONE);
        assert_eq!((m.ior, m.specular_reflectance), (ior, Vec3::splat(0.3)));
        assert!(scene::check_material(m).is_ok());
    }
}

#[test]
fn shipped_glass_and_mirror_mean_what_they_meant() {
    // scenes/cornell_specular/scene.mtl: illum 7 with d 0, and illum 3 with Ks 0.9.
    let lib = parse(
        "newmtl glass\nKa 0 0 0\nKd 0 0 0\nKs 1 1 1\nKe 0 0 0\nNi 1.5\nd 0\nillum 7\n\
newmtl mirror\nKd 0 0 0\nKs 0.9 0.9 0.9\nNi 1\nd 1\nillum 3\n",
    );
    let g = material(&lib, "glass");
    assert_eq!((g.transmittance, g.ior, g.specular_reflectance), (1.0, 1.5, Vec3::ONE));
    let m = material(&lib, "mirror");
    assert_eq!((m.transmittance, m.specular_reflectance), (0.0, Vec3::splat(0.9)));
}

// ---------------------------------------------------------------------------------------------------
// Tr, Tf, d

#[test]
fn tr_is_one_minus_d_and_d_wins_when_they_disagree() {
    let lib = parse("newmtl a\nKs 0.5 0.5 0.5\nNi 1.5\nTr 0.25\nnewmtl b\nKs 0.5 0.5 0.5\nNi 1.5\nd 0.5\nTr 0.9\n");
    assert_relative_eq!(material(&lib, "a").transmittance, 0.25);
    assert_relative_eq!(material(&lib, "b").transmittance, 0.5);
    assert_eq!(lib.warnings.iter().filter(|w| w.contains("disagree") && w.contains("`b`")).count(), 1);
    // McGuire's opaque materials write `d 1.0000`, `Tr 0.0000`, `Tf 1 1 1`: opaque.
    let lib = parse("newmtl light\n\tNi 1.5000\n\td 1.0000\n\tTr 0.0000\n\tTf 1.0000 1.0000 1.0000 \n\tillum 2\n");
    assert!(!material(&lib, "light").is_dielectric());
}

#[test]
fn tr_0_is_opaque_and_tr_1_alone_is_read_as_the_opacity_3ds_max_and_meshlab_write() {
    let lib = parse(
        "newmtl a\nKd 0.5 0.5 0.5\nTr 0\nnewmtl meshlab\nKd 0.5 0.5 0.5\nTr 1.000000\nillum 2\n\
newmtl glass\nKs 1 1 1\nNi 1.5\nTr 1\nillum 7\n",
    );
    assert!(!material(&lib, "a").is_dielectric());
    assert!(!material(&lib, "meshlab").is_dielectric());
    let said: Vec<&String> = lib.warnings.iter().filter(|w| w.contains("`Tr 1`")).collect();
    assert!(said.len() == 1 && said[0].contains("`meshlab`") && said[0].contains("scene.mtl"), "{:?}", lib.warnings);
    // With a transparent illum model, Tr 1 keeps its usual meaning: fully transparent.
    assert_relative_eq!(material(&lib, "glass").transmittance, 1.0);
}

#[test]
fn a_nameless_newmtl_is_a_warning_with_its_line() {
    let lib = parse("newmtl\nKd 0.5 0.5 0.5\nnewmtl a\nKd 0.25 0.25 0.25\n");
    assert_eq!(material(&lib, "a").diffuse_reflectance, Vec3::splat(0.25));
    let said: Vec<&String> = lib.warnings.iter().filter(|w| w.contains("without a name")).collect();
    assert!(said.len() == 1 && said[0].contains("scene.mtl:1:"), "{:?}", lib.warnings);
}

#[test]
fn texture_paths_from_the_exporters_machine_fall_back_to_the_file_next_to_the_mtl() {
    let (dir, r) = load_scene(
        "newmtl wall\nKd 1 1 1\nmap_Kd C:\\Users\\bob\\proj\\maps\\Brick.PNG\nnewmtl wall2\nmap_Kd /home/bob/brick.png\n",
        &[("brick.png", &png_bytes(1, 1, &[128]))],
    );
    let s = r.expect("scene loads");
    let wall = s.materials.iter().find(|m| m.name == "wall").unwrap();
    assert_eq!(wall.textures.diffuse.as_ref().unwrap().path, dir.path().join("brick.png"));
    let said: Vec<&String> = s.warnings.iter().filter(|w| w.contains("not found as written")).collect();
    // One warning per MTL file, however many maps were found that way.
    assert!(said.len() == 1 && said[0].contains("m.mtl:6:") && said[0].contains("1 more"), "{:?}", s.warnings);
}

#[test]
fn tf_filters_what_d_lets_through() {
    let lib = parse("newmtl green_glass\nKd 0 0 0\nKs 1 1 1\nNi 1.5\nd 0\nTf 0.5 1 0.5\nillum 4\n");
    let g = material(&lib, "green_glass");
    assert_eq!((g.transmittance, g.transmission_filter), (1.0, Vec3::new(0.5, 1.0, 0.5)));
}

// ---------------------------------------------------------------------------------------------------
// Texture maps

#[test]
fn maps_are_recorded_relative_to_the_mtl_folder_with_options_skipped_once() {
    let lib = parse(
        "newmtl leaf\nKd 1 1 1\nmap_Kd -bm 1 textures/leaf diffuse.png\nmap_d -s 2 2 textures\\leaf_mask.png\n\
newmtl screen\nmap_Ke -o 0.5 0.5 screen.tga\nmap_Kd -bm 2 screen.jpg\n",
    );
    let leaf = material(&lib, "leaf");
    let kd_map = leaf.textures.diffuse.as_ref().expect("map_Kd");
    assert_eq!(kd_map.path, Path::new("/scenes/box/textures/leaf diffuse.png"));
    assert_eq!(kd_map.factor, Vec3::ONE);
    assert_eq!(kd_map.source.line, 3);
    let d_map = leaf.textures.opacity.as_ref().expect("map_d");
    assert_eq!(d_map.path, Path::new("/scenes/box/textures/leaf_mask.png"));
    // Kd 1 with a texture: accepted without a warning; the untextured fallback sits under the ceiling.
    assert_eq!(leaf.diffuse_reflectance, Vec3::splat(ALBEDO_CEILING));
    assert!(!lib.warnings.iter().any(|w| w.contains("clamped")), "{:?}", lib.warnings);
    let screen = material(&lib, "screen");
    let ke_map = screen.textures.emission.as_ref().expect("map_Ke");
    assert_eq!((ke_map.path.as_path(), ke_map.factor), (Path::new("/scenes/box/screen.tga"), Vec3::ONE));
    let options: Vec<&String> = lib.warnings.iter().filter(|w| w.contains("texture options")).collect();
    assert_eq!(options.len(), 1, "{:?}", lib.warnings);
    assert!(options[0].contains("scene.mtl") && options[0].contains("-bm") && options[0].contains("-s"));
}

#[test]
fn a_missing_texture_warns_with_its_name_and_the_material_falls_back_to_kd() {
    let lib = parse("newmtl wall\nKd 0.6 0.5 0.4\nmap_Kd missing_wood.jpg\n");
    let wall = material(&lib, "wall");
    let mut cache = TextureCache::new();
    let (maps, warnings) = MaterialMaps::resolve(wall, &mut cache);
    assert_eq!(warnings.len(), 1);
    let text = warnings[0].to_string();
    assert!(text.contains("missing_wood.jpg") && text.contains("`wall`") && text.contains("Kd"), "{text}");
    assert!(!maps.has_diffuse_texture());
    assert_eq!(maps.albedo_at(Vec2::new(0.3, 0.3), 0.0), Vec3::new(0.6, 0.5, 0.4));
    assert_eq!(maps.mean_albedo_over(Vec2::ZERO, Vec2::X, Vec2::Y), Vec3::new(0.6, 0.5, 0.4));
    // A second material naming the same file: the cache does not warn again.
    let (_, again) = MaterialMaps::resolve(wall, &mut cache);
    assert!(again.is_empty());
}

#[test]
fn a_textured_scene_loads_its_kd_1_material_and_pass_one_sees_the_exact_mean() {
    // 2×2 grey checker, sRGB 255 and 0 → linear 1 and 0, with Kd 1: the mean albedo over either half
    // of the square is ½ · min(1, 0.98) = 0.49 (the product meets the ceiling per texel).
    let png = png_bytes(2, 2, &[255, 0, 0, 255]);
    let (_dir, result) = load_scene("newmtl wall\nKd 1 1 1\nmap_Kd checker.png\n", &[("checker.png", &png)]);
    let s = result.expect("a textured Kd 1 material loads");
    assert!(!s.warnings.iter().any(|w| w.contains("clamped")), "{:?}", s.warnings);
    let wall = s.materials.iter().find(|m| m.name == "wall").expect("wall");
    let (maps, warnings) = MaterialMaps::resolve(wall, &mut TextureCache::new());
    assert!(warnings.is_empty(), "{warnings:?}");
    let (a, b, c) = (Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0), Vec2::new(1.0, 1.0));
    assert_close(maps.mean_albedo_over(a, b, c), Vec3::splat(0.49));
    // At texel centres pass two sees the texel: top-left (v = 0.75) is the white one.
    assert_close(maps.albedo_at(Vec2::new(0.25, 0.75), 0.0), Vec3::splat(ALBEDO_CEILING));
    assert_close(maps.albedo_at(Vec2::new(0.75, 0.75), 0.0), Vec3::ZERO);
}

#[test]
fn the_alpha_of_map_kd_cuts_out_when_there_is_no_map_d() {
    let image = image::RgbaImage::from_raw(2, 1, vec![200, 200, 200, 255, 200, 200, 200, 0]).expect("size");
    let mut png = Vec::new();
    image.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png).expect("encode");
    let (_dir, result) = load_scene("newmtl wall\nKd 1 1 1\nmap_Kd leaf.png\n", &[("leaf.png", &png)]);
    let s = result.expect("loads");
    let wall = s.materials.iter().find(|m| m.name == "wall").expect("wall");
    let (maps, _) = MaterialMaps::resolve(wall, &mut TextureCache::new());
    assert!(maps.has_opacity());
    assert_eq!(maps.opacity_at(Vec2::new(0.25, 0.5), 0.0), 1.0);
    assert_eq!(maps.opacity_at(Vec2::new(0.75, 0.5), 0.0), 0.0);
}

#[test]
fn map_d_is_read_linearly_from_its_first_channel() {
    // Grey 128 without alpha: opacity 128/255 (data, not sRGB colour).
    let png = png_bytes(1, 1, &[128]);
    let (_dir, result) = load_scene("newmtl wall\nKd 0.5 0.5 0.5\nmap_d mask.png\n", &[("mask.png", &png)]);
    let s = result.expect("loads");
    let wall = s.materials.iter().find(|m| m.name == "wall").expect("wall");
    let (maps, _) = MaterialMaps::resolve(wall, &mut TextureCache::new());
    assert_relative_eq!(maps.opacity_at(Vec2::new(0.5, 0.5), 0.0), 128.0 / 255.0, max_relative = 1e-6);
}

#[test]
fn png_jpeg_and_tga_textures_decode_through_the_srgb_curve() {
    let dir = tempfile::tempdir().expect("temp dir");
    let image = image::RgbImage::from_pixel(8, 8, image::Rgb([188, 188, 188]));
    for (name, format) in
        [("t.png", image::ImageFormat::Png), ("t.jpg", image::ImageFormat::Jpeg), ("t.tga", image::ImageFormat::Tga)]
    {
        let path = dir.path().join(name);
        image.save_with_format(&path, format).expect("encode");
        let t = Texture::load(&path, ColorEncoding::Srgb).expect("decodes");
        // JPEG is lossy: a flat 8×8 block may come back ±1 code value (≈0.004 linear near 0.5).
        let expected = srgb_to_linear(188.0 / 255.0);
        assert_relative_eq!(t.bilinear(Vec2::splat(0.5), 0).x, expected, max_relative = 0.01);
        assert!(!t.has_alpha);
    }
    let broken = dir.path().join("broken.png");
    std::fs::write(&broken, b"not a png").expect("write");
    let message = Texture::load(&broken, ColorEncoding::Srgb).unwrap_err().to_string();
    assert!(message.contains("broken.png"), "{message}");
}

// ---------------------------------------------------------------------------------------------------
// Clamps and errors

#[test]
fn kd_above_one_without_texture_is_clamped_with_one_warning_naming_file_material_and_value() {
    let (_dir, result) = load_scene("newmtl wall\nKd 1.2 1.2 1.2\n", &[]);
    let s = result.expect("clamped, not refused");
    let wall = s.materials.iter().find(|m| m.name == "wall").expect("wall");
    assert_eq!(wall.diffuse_reflectance, Vec3::splat(ALBEDO_CEILING));
    let clamped: Vec<&String> = s.warnings.iter().filter(|w| w.contains("clamped")).collect();
    assert_eq!(clamped.len(), 1, "{:?}", s.warnings);
    assert!(
        clamped[0].contains("m.mtl") && clamped[0].contains("`wall`") && clamped[0].contains("1.2"),
        "{}",
        clamped[0]
    );
}

#[test]
fn glossy_kd_plus_ks_above_one_is_clamped_not_refused() {
    // McGuire's CornellBox-Glossy sphere (illum 2).
    let lib = parse(
        "newmtl sphere\n\tNs 40.0000\n\tNi 1.5000\n\td 1.0000\n\tTr 0.0000\n\tTf 1.0000 1.0000 1.0000 \n\tillum 2\n\
\tKa 0.4860 0.6310 0.6630\n\tKd 0.4860 0.6310 0.6630\n\tKs 0.9000 0.9000 0.9000\n\tKe 0.0000 0.0000 0.0000\n",
    );
    let m = material(&lib, "sphere");
    assert!(scene::check_material(m).is_ok());
    assert_relative_eq!(
        (m.diffuse_reflectance + m.specular_reflectance).max_element(),
        ALBEDO_CEILING,
        max_relative = 1e-6
    );
    assert_eq!(lib.warnings.iter().filter(|w| w.contains("clamped")).count(), 1);
}

#[test]
fn negative_or_non_finite_numbers_are_errors_with_file_and_line() {
    for (text, line) in [
        ("newmtl a\nKd 0.5 0.5 0.5\nKd -0.1 0.5 0.5\n", 3),
        ("newmtl a\nKs nan 0 0\n", 2),
        ("newmtl a\n\n\nNi -1\n", 4),
        ("newmtl a\nd 1.5\n", 2),
        ("newmtl a\nillum seven\n", 2),
        ("newmtl a\nmap_Kd -bm 1\n", 2),
    ] {
        let err = mtl::parse(Path::new("scene.mtl"), text).unwrap_err().to_string();
        assert!(err.starts_with(&format!("scene.mtl:{line}:")), "{text:?}: {err}");
    }
    // Through a scene: the error names the MTL file and line.
    let (_dir, result) = load_scene("newmtl wall\nKd -0.1 0.5 0.5\n", &[]);
    let message = result.unwrap_err().to_string();
    assert!(message.contains("m.mtl:5:"), "{message}");
}

#[test]
fn unused_statements_are_warned_once_per_file() {
    let lib =
        parse("Ka 0 0 0\nnewmtl a\nKa 1 1 1\nmap_bump b.png\nnewmtl b\nKa 1 1 1\nPr 0.5\nmap_bump c.png\nillum 2\n");
    let ignoring: Vec<&String> = lib.warnings.iter().filter(|w| w.contains("ignoring")).collect();
    assert_eq!(ignoring.len(), 1, "{:?}", lib.warnings);
    assert!(ignoring[0].starts_with("/scenes/box/scene.mtl: ignoring"), "{}", ignoring[0]);
    for word in ["Ka", "map_bump", "Pr", "not used by radray"] {
        assert!(ignoring[0].contains(word), "{}", ignoring[0]);
    }
    assert_eq!(ignoring[0].matches("map_bump").count(), 1);
}

#[test]
fn windows_line_endings_tabs_and_negative_indices_load_as_in_the_mcguire_files() {
    let dir = tempfile::tempdir().expect("temp dir");
    let obj = "mtllib box.mtl\r\nv -1 0 -1\r\nv 1 0 -1\r\nv 1 0 1\r\nv -1 0 1\r\nv -1 2 -1\r\nv 1 2 -1\r\n\
g floor\r\nusemtl floor\r\nf -6 -3 -4 -5\r\ng light\r\nusemtl light\r\nf -2 -1 -5 -6\r\n";
    let mtl = "newmtl floor\r\n\tKa 0.7 0.7 0.7 # White\r\n\tKd 0.725 0.71 0.68\r\n\tillum 2\r\n\
newmtl light\r\n  Kd 0.78 0.78 0.78\r\n  Ke 17 12 4\r\n";
    std::fs::write(dir.path().join("box.obj"), obj).expect("write");
    std::fs::write(dir.path().join("box.mtl"), mtl).expect("write");
    std::fs::write(dir.path().join("scene.toml"), "[[mesh]]\nobj = \"box.obj\"\n").expect("write");
    let s = scene::load(&dir.path().join("scene.toml")).expect("loads");
    assert_eq!(s.surfaces.len(), 2);
    let floor = s.materials.iter().find(|m| m.name == "floor").expect("floor");
    assert_eq!(floor.diffuse_reflectance, Vec3::new(0.725, 0.71, 0.68));
    assert!(s.materials.iter().any(|m| m.name == "light" && m.emitted_radiance == Vec3::new(17.0, 12.0, 4.0)));
    assert!(s.warnings.iter().any(|w| w.contains("box.mtl: ignoring Ka")), "{:?}", s.warnings);
}

// ---------------------------------------------------------------------------------------------------
// Element mean albedo

#[test]
fn element_mean_albedo_equals_the_exact_average_over_a_known_texture() {
    // 4×4 texture, texel (i, j) = i + 4j (row j from the top), as linear values.
    let texels: Vec<Vec4> = (0..16).map(|k| Vec4::new(k as f32, 0.0, 0.0, 1.0)).collect();
    let t = Texture::from_linear(4, 4, texels, false);
    // Full square: the mean of 0..15.
    let (a, b, c, d) = (Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0), Vec2::new(1.0, 1.0), Vec2::new(0.0, 1.0));
    let halves = t.mean_over_triangle(a, b, c).x + t.mean_over_triangle(a, c, d).x;
    assert_relative_eq!(halves / 2.0, 7.5, max_relative = 1e-9);
    // Lower-right half in texel space (x + y ≥ 4, y down): texels with i + j ≥ 4 fully (area 1) and the
    // anti-diagonal ones i + j = 3 by half. Sum of values · areas over area 8.
    let mut sum = 0.0f64;
    for j in 0..4 {
        for i in 0..4 {
            let weight = if i + j >= 4 {
                1.0
            } else if i + j == 3 {
                0.5
            } else {
                0.0
            };
            sum += weight * (i + 4 * j) as f64;
        }
    }
    assert_relative_eq!(t.mean_over_triangle(a, b, c).x as f64, sum / 8.0, max_relative = 1e-6);
    // A triangle inside one texel is that texel; one spanning two tiles (wrap) averages the repeat.
    let inside = t.mean_over_triangle(Vec2::new(0.26, 0.74), Vec2::new(0.49, 0.74), Vec2::new(0.26, 0.51));
    assert_relative_eq!(inside.x, 5.0);
    let wrapped = t.mean_over_triangle(Vec2::new(1.0, 0.0), Vec2::new(2.0, 0.0), Vec2::new(2.0, 1.0));
    assert_relative_eq!(wrapped.x as f64, sum / 8.0, max_relative = 1e-6);
}

/// Σ w(i, j)·t(i, j) / Σ w over an n×n level whose texel (i, j) (row j from the top) holds `value`,
/// with w = 1 for i + j ≥ n, ½ on the anti-diagonal i + j = n − 1, else 0: the exact area average over
/// the lower-right half triangle in texel space (y down), uv (0, 0), (1, 0), (1, 1).
fn lower_right_half_mean(n: usize, value: impl Fn(usize, usize) -> f64) -> f64 {
    let mut sum = 0.0f64;
    for j in 0..n {
        for i in 0..n {
            let weight = if i + j >= n {
                1.0
            } else if i + j + 1 == n {
                0.5
            } else {
                0.0
            };
            sum += weight * value(i, j);
        }
    }
    sum / (n * n) as f64 * 2.0
}

#[test]
fn a_large_triangles_mean_is_the_exact_average_of_the_mip_level_matched_to_its_footprint() {
    // 64×64 texels, t(i, j) = (7i + 13j) mod 17 + (i·j mod 5)/4: no two neighbours alike. The lower-right
    // half triangle's bounding box covers 64² = 4096 texels of level 0, over MEAN_TEXEL_BUDGET (1024),
    // and 32² = 1024 of level 1: its mean is the exact area average of level 1's texels, each the exact
    // mean of a 2×2 block of level 0. Only the diagonal texels differ from the level-0 average.
    let n = 64usize;
    let value = |i: usize, j: usize| ((7 * i + 13 * j) % 17) as f64 + ((i * j) % 5) as f64 / 4.0;
    let texels: Vec<Vec4> = (0..n * n).map(|k| Vec4::new(value(k % n, k / n) as f32, 0.0, 0.0, 1.0)).collect();
    let t = Texture::from_linear(n as u32, n as u32, texels, false);
    assert_eq!(radray::material::texture::MEAN_TEXEL_BUDGET, 1024.0);
    let (a, b, c, d) = (Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0), Vec2::new(1.0, 1.0), Vec2::new(0.0, 1.0));
    assert_eq!(t.mean_level(a, b, c), 1);
    let level1 = |i: usize, j: usize| {
        (value(2 * i, 2 * j) + value(2 * i + 1, 2 * j) + value(2 * i, 2 * j + 1) + value(2 * i + 1, 2 * j + 1)) / 4.0
    };
    assert_relative_eq!(t.mean_over_triangle(a, b, c).x as f64, lower_right_half_mean(32, level1), max_relative = 1e-6);
    // Edges on level-1 texel borders: the two halves of the square average to the exact level-0 mean.
    let exact: f64 = (0..n * n).map(|k| value(k % n, k / n)).sum::<f64>() / (n * n) as f64;
    let halves = t.mean_over_triangle(a, b, c).x as f64 + t.mean_over_triangle(a, c, d).x as f64;
    assert_relative_eq!(halves / 2.0, exact, max_relative = 1e-6);
    // Within the budget (bounding box 16² texels of level 0), the exact level-0 average.
    let quarter = [Vec2::new(0.0, 0.75), Vec2::new(0.25, 0.75), Vec2::new(0.25, 1.0)];
    assert_eq!(t.mean_level(quarter[0], quarter[1], quarter[2]), 0);
    let m = t.mean_over_triangle(quarter[0], quarter[1], quarter[2]).x as f64;
    assert_relative_eq!(m, lower_right_half_mean(16, value), max_relative = 1e-6);
    // Four tiles of a 256² texture (1024² texels at level 0): level 5, whose 8×8 texels a tile holds,
    // is the finest within budget (32² texels), so one mean visits at most 1024 texels.
    let big = Texture::from_linear(256, 256, vec![Vec4::ONE; 256 * 256], false);
    assert_eq!(big.mean_level(Vec2::ZERO, Vec2::new(4.0, 0.0), Vec2::new(4.0, 4.0)), 5);
    assert_relative_eq!(big.mean_over_triangle(Vec2::ZERO, Vec2::new(4.0, 0.0), Vec2::new(4.0, 4.0)).x, 1.0);
}
