//! Pictures of flights, downstream of the simulator and the evaluation: the robot is replayed
//! kinematically from a flight's poses (no physics is stepped here) in MuJoCo's own offscreen
//! renderer (EGL; Mesa's software rasterizer works without a GPU), in a copy of the model with
//! scenery added (sky, ground grid, the reference drawn as markers). Writes PNG snapshots, overlays
//! of snapshots along a path, and video through ffmpeg.

mod camera;
mod image;
mod renderer;
mod scenery;
mod video;

pub use camera::{CameraView, chase_cameras, framing_camera};
pub use image::{Frame, write_png};
pub use renderer::{FlightRenderer, Marker, Pose};
pub use scenery::render_model_mjcf;
pub use video::{VideoEncoder, ffmpeg_available};

/// Why a picture or a video could not be made.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error(
        "offscreen rendering is unavailable ({0}); it needs EGL with Mesa (Debian: libegl1 libegl-mesa0 libgl1-mesa-dri, or `make report-deps`)"
    )]
    NoOpenGl(String),
    #[error("the render model does not compile: {0}")]
    Model(String),
    #[error("rendering failed: {0}")]
    Render(String),
    #[error("the video needs ffmpeg on PATH (Debian: `apt-get install ffmpeg`, or `make report-deps`)")]
    NoFfmpeg,
    #[error("ffmpeg failed writing '{path}': {message}")]
    Video { path: String, message: String },
    #[error("cannot write '{path}': {source}")]
    Write { path: String, source: std::io::Error },
    #[error("nothing to draw: {0}")]
    Empty(&'static str),
}
