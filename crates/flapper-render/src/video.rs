//! Video: frames piped as raw RGB into ffmpeg, which writes H.264 in MP4 (yuv420p, fast start), the
//! format every browser plays. Written to a temporary name and renamed when complete.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

use crate::RenderError;
use crate::image::Frame;

/// Whether `ffmpeg` runs from PATH.
pub fn ffmpeg_available() -> bool {
    Command::new("ffmpeg")
        .arg("-version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// An MP4 being written.
pub struct VideoEncoder {
    child: Child,
    temporary: PathBuf,
    path: PathBuf,
    size: (usize, usize),
}

impl VideoEncoder {
    /// Starts ffmpeg for `width` x `height` frames (even numbers, for yuv420p) at `fps`.
    pub fn start(path: &Path, width: usize, height: usize, fps: u32) -> Result<Self, RenderError> {
        if !ffmpeg_available() {
            return Err(RenderError::NoFfmpeg);
        }
        let failed = |message: String| RenderError::Video { path: path.display().to_string(), message };
        if width % 2 == 1 || height % 2 == 1 {
            return Err(failed(format!("H.264 in yuv420p needs even sizes, got {width}x{height}")));
        }
        let name = path.file_name().ok_or_else(|| failed("not a file name".into()))?.to_string_lossy();
        let temporary = path.with_file_name(format!(".tmp-{name}"));
        let child = Command::new("ffmpeg")
            .args([
                "-y",
                "-loglevel",
                "error",
                "-f",
                "rawvideo",
                "-pix_fmt",
                "rgb24",
                "-s",
                &format!("{width}x{height}"),
            ])
            .args([
                "-r",
                &fps.to_string(),
                "-i",
                "-",
                "-c:v",
                "libx264",
                "-preset",
                "medium",
                "-crf",
                "23",
                "-pix_fmt",
                "yuv420p",
            ])
            .args(["-movflags", "+faststart", "-f", "mp4"])
            .arg(&temporary)
            .stdin(Stdio::piped())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| failed(e.to_string()))?;
        Ok(Self { child, temporary, path: path.to_owned(), size: (width, height) })
    }

    pub fn push(&mut self, frame: &Frame) -> Result<(), RenderError> {
        if (frame.width, frame.height) != self.size {
            return Err(self.fail(format!(
                "frame of {}x{} in a {}x{} video",
                frame.width, frame.height, self.size.0, self.size.1
            )));
        }
        let stdin = self.child.stdin.as_mut().expect("stdin is piped until finish");
        if let Err(e) = stdin.write_all(&frame.rgb) {
            return Err(self.fail(format!("the encoder stopped: {e}")));
        }
        Ok(())
    }

    /// Waits for ffmpeg and moves the file into place.
    pub fn finish(mut self) -> Result<PathBuf, RenderError> {
        drop(self.child.stdin.take());
        let output = self.child.wait_with_output();
        let failed = |message: String| RenderError::Video { path: self.path.display().to_string(), message };
        match output {
            Ok(o) if o.status.success() => {
                std::fs::rename(&self.temporary, &self.path).map_err(|e| failed(e.to_string()))?;
                Ok(self.path)
            }
            Ok(o) => {
                let _ = std::fs::remove_file(&self.temporary);
                Err(failed(String::from_utf8_lossy(&o.stderr).trim().to_owned()))
            }
            Err(e) => Err(failed(e.to_string())),
        }
    }

    fn fail(&mut self, message: String) -> RenderError {
        let _ = self.child.kill();
        let _ = self.child.wait();
        let _ = std::fs::remove_file(&self.temporary);
        RenderError::Video { path: self.path.display().to_string(), message }
    }
}
