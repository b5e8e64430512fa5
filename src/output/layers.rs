//! Layered OpenEXR for compositing: one single-part file with the beauty image as R, G, B and every
//! other layer as `<layer>.R/G/B` (and `depth.Z`), the channel naming Nuke, Blender and Natron read as
//! layers. All channels are float32, uncompressed.

use std::io::Cursor;
use std::path::{Path, PathBuf};

use exr::prelude::{
    AnyChannel, AnyChannels, Encoding, FlatSamples, Image as ExrImage, Layer, LayerAttributes, SmallVec,
};
use glam::Vec3;

use super::{write_bytes, OutputError};

/// One image's layers: the beauty (written as plain R, G, B), named RGB layers and named scalar
/// channels, all `width_px × height_px`, row-major from the top-left.
#[derive(Clone, Debug, Default)]
pub struct Layers {
    pub width_px: u32,
    pub height_px: u32,
    pub beauty: Vec<Vec3>,
    /// (layer name, pixels), written as `name.R`, `name.G`, `name.B`.
    pub rgb: Vec<(String, Vec<Vec3>)>,
    /// (channel name such as `depth.Z`, pixels).
    pub scalar: Vec<(String, Vec<f32>)>,
}

/// Encodes the layers as one OpenEXR file in memory.
pub fn encode_layered_exr(layers: &Layers, path: &Path) -> Result<Vec<u8>, OutputError> {
    let pixels = layers.width_px as usize * layers.height_px as usize;
    let inconsistent = |found: usize| OutputError::InconsistentImage {
        path: path.to_path_buf(),
        width_px: layers.width_px,
        height_px: layers.height_px,
        pixels: found,
    };
    let mut channels: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
    let mut add_rgb = |prefix: &str, values: &[Vec3]| -> Result<(), OutputError> {
        if values.len() != pixels {
            return Err(inconsistent(values.len()));
        }
        for (c, name) in ["R", "G", "B"].iter().enumerate() {
            let samples = values.iter().map(|v| v[c]).collect();
            channels.push(AnyChannel::new(format!("{prefix}{name}").as_str(), FlatSamples::F32(samples)));
        }
        Ok(())
    };
    add_rgb("", &layers.beauty)?;
    for (name, values) in &layers.rgb {
        add_rgb(&format!("{name}."), values)?;
    }
    for (name, values) in &layers.scalar {
        if values.len() != pixels {
            return Err(inconsistent(values.len()));
        }
        channels.push(AnyChannel::new(name.as_str(), FlatSamples::F32(values.clone())));
    }
    let layer = Layer::new(
        (layers.width_px as usize, layers.height_px as usize),
        LayerAttributes::default(),
        Encoding::UNCOMPRESSED,
        AnyChannels::sort(channels),
    );
    let image = ExrImage::from_layer(layer);
    let mut bytes = Cursor::new(Vec::new());
    exr::image::write::WritableImage::write(&image)
        .to_buffered(&mut bytes)
        .map_err(|source| OutputError::ExrEncode { path: path.to_path_buf(), source })?;
    Ok(bytes.into_inner())
}

/// Writes the layers as one OpenEXR file, atomically.
pub fn write_layered_exr(layers: &Layers, path: &Path) -> Result<(), OutputError> {
    let bytes = encode_layered_exr(layers, path)?;
    write_bytes(path, &bytes)
}

/// Every channel of an EXR file's first layer by name, as float32 (for tests and tools).
pub fn read_exr_channels(path: &Path) -> Result<Vec<(String, Vec<f32>)>, OutputError> {
    let decode = |source| OutputError::ExrDecode { path: PathBuf::from(path), source };
    let image = exr::image::read::read_first_flat_layer_from_file(path).map_err(decode)?;
    Ok(image
        .layer_data
        .channel_data
        .list
        .iter()
        .map(|c| (c.name.to_string(), c.sample_data.values_as_f32().collect()))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layers_read_back_under_compositor_names() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("layers.exr");
        let beauty = vec![Vec3::new(1.0, 2.0, 3.0), Vec3::new(4.0, 5.0, 6.0)];
        let layers = Layers {
            width_px: 2,
            height_px: 1,
            beauty: beauty.clone(),
            rgb: vec![("direct".into(), vec![Vec3::ONE, Vec3::ZERO])],
            scalar: vec![("depth.Z".into(), vec![7.0, 8.0])],
        };
        write_layered_exr(&layers, &path).unwrap();
        let channels = read_exr_channels(&path).unwrap();
        let names: Vec<&str> = channels.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["B", "G", "R", "depth.Z", "direct.B", "direct.G", "direct.R"]);
        assert_eq!(channels[2].1, vec![1.0, 4.0]);
        assert_eq!(channels[3].1, vec![7.0, 8.0]);
        // The plain reader sees the beauty.
        assert_eq!(super::super::read_image(&path).unwrap().pixels, beauty);
        let short = Layers { scalar: vec![("depth.Z".into(), vec![1.0])], ..layers };
        assert!(matches!(encode_layered_exr(&short, &path), Err(OutputError::InconsistentImage { .. })));
    }
}
