//! A rendered frame (RGB and depth) and PNG output.

use crate::RenderError;

/// One rendered picture: `rgb` row-major from the top-left, 3 bytes per pixel; `depth_m` the distance
/// of each pixel from the camera (metres).
#[derive(Debug, Clone)]
pub struct Frame {
    pub width: usize,
    pub height: usize,
    pub rgb: Vec<u8>,
    pub depth_m: Vec<f32>,
}

impl Frame {
    /// Keeps, pixel by pixel, whichever of the two frames is nearer the camera: snapshots of the
    /// robot at several instants, taken from one camera, merge into one picture with correct
    /// occlusion (the scenery is the same in every snapshot).
    pub fn merge_nearest(&mut self, other: &Frame) {
        assert_eq!((self.width, self.height), (other.width, other.height), "frames of one overlay share a size");
        for k in 0..self.depth_m.len() {
            let theirs = other.depth_m[k];
            if theirs < self.depth_m[k] {
                self.depth_m[k] = theirs;
                self.rgb[3 * k..3 * k + 3].copy_from_slice(&other.rgb[3 * k..3 * k + 3]);
            }
        }
    }
}

/// Writes the frame as an 8-bit RGB PNG (complete or absent: temp file and rename).
pub fn write_png(frame: &Frame, path: &std::path::Path) -> Result<(), RenderError> {
    let failed = |e: std::io::Error| RenderError::Write { path: path.display().to_string(), source: e };
    let mut bytes = Vec::new();
    {
        let mut encoder = mujoco_rs::renderer::png::Encoder::new(&mut bytes, frame.width as u32, frame.height as u32);
        encoder.set_color(mujoco_rs::renderer::png::ColorType::Rgb);
        encoder.set_depth(mujoco_rs::renderer::png::BitDepth::Eight);
        encoder.set_compression(mujoco_rs::renderer::png::Compression::Balanced);
        let mut writer = encoder.write_header().map_err(|e| failed(std::io::Error::other(e)))?;
        writer.write_image_data(&frame.rgb).map_err(|e| failed(std::io::Error::other(e)))?;
    }
    flapper_plot::write_atomically(path, &bytes).map_err(failed)
}
