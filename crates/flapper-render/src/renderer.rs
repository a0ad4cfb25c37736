//! The renderer: poses the robot in the render model and draws it offscreen with MuJoCo's renderer.

use flapper_sim::{ActuatedJoint, N_ACTUATED_JOINTS, RobotModel};
use mujoco_rs::prelude::*;
use mujoco_rs::renderer::MjRenderer;

use crate::RenderError;
use crate::camera::CameraView;
use crate::image::Frame;
use crate::scenery::{MAX_HEIGHT_PX, MAX_WIDTH_PX, render_model_mjcf};

/// Where the robot is and how its joints stand at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    pub position_m: [f64; 3],
    /// Body orientation as a unit quaternion (w, x, y, z).
    pub orientation_wxyz: [f64; 4],
    /// Joint angles in the paper's order q1..q5 (rad).
    pub joint_positions_rad: [f64; N_ACTUATED_JOINTS],
}

impl Pose {
    /// From roll, pitch and yaw (rad, the convention of `flapper_sim::quat_from_euler`).
    pub fn from_euler(
        position_m: [f64; 3],
        euler_rad: [f64; 3],
        joint_positions_rad: [f64; N_ACTUATED_JOINTS],
    ) -> Self {
        let q = flapper_sim::quat_from_euler(euler_rad[0], euler_rad[1], euler_rad[2]);
        Self { position_m, orientation_wxyz: flapper_sim::quat_to_wxyz(q), joint_positions_rad }
    }
}

/// A sphere drawn into the scene (a reference point, a target), optionally labelled.
#[derive(Debug, Clone, PartialEq)]
pub struct Marker {
    pub position_m: [f64; 3],
    pub radius_m: f64,
    pub rgba: [f32; 4],
}

/// The body frame as drawn by the annotation: label, axis in the body frame, colour.
const BODY_AXES: [(&str, [f64; 3], [f32; 4]); 3] = [
    ("x (forward)", [1.0, 0.0, 0.0], [0.85, 0.1, 0.1, 1.0]),
    ("y (left)", [0.0, 1.0, 0.0], [0.1, 0.6, 0.1, 1.0]),
    ("z (up)", [0.0, 0.0, 1.0], [0.1, 0.2, 0.85, 1.0]),
];

/// Where each joint's label sits, from its anchor, in the body frame (m), order q1..q5.
const JOINT_LABEL_OFFSETS_M: [[f64; 3]; N_ACTUATED_JOINTS] =
    [[0.0, 0.12, 0.2], [0.15, 0.3, 0.08], [0.0, -0.12, 0.2], [0.15, -0.3, 0.08], [-0.15, 0.0, 0.18]];

/// Adds a connector geom (arrow or line) from `from` to `to`, with an optional label.
fn add_connector(
    scene: &mut MjvScene,
    kind: MjtGeom,
    width: f64,
    from: [f64; 3],
    to: [f64; 3],
    rgba: [f32; 4],
    label: &str,
) -> Result<(), RenderError> {
    // SAFETY: no material, texture or object index is set (all stay -1).
    let geom = unsafe { scene.try_create_geom(kind, None, None, None, Some(rgba)) }
        .map_err(|e| RenderError::Render(format!("{e:?}")))?;
    geom.connect(width, from, to);
    geom.set_label(label).map_err(|e| RenderError::Render(format!("{e:?}")))
}

/// Space for markers, arrows and labels drawn besides the model.
const MAX_DECORATIONS: usize = 4000;

/// Draws the robot at given poses. One per thread (it owns an OpenGL context).
pub struct FlightRenderer {
    data: MjData<Box<MjModel>>,
    renderer: MjRenderer,
    base_qpos: usize,
    /// The five joints' ids and qpos addresses in the render model, order q1..q5.
    joint_ids: [usize; N_ACTUATED_JOINTS],
    joint_qpos: [usize; N_ACTUATED_JOINTS],
    width: usize,
    height: usize,
    markers: Vec<Marker>,
    annotated: bool,
}

impl FlightRenderer {
    /// A renderer of `robot` (with the scenery added) drawing `width` x `height` pixels.
    pub fn new(robot: &RobotModel, width: usize, height: usize) -> Result<Self, RenderError> {
        if width == 0 || height == 0 || width > MAX_WIDTH_PX || height > MAX_HEIGHT_PX {
            return Err(RenderError::Render(format!(
                "a frame must be 1x1 to {MAX_WIDTH_PX}x{MAX_HEIGHT_PX} pixels, got {width}x{height}"
            )));
        }
        let text = render_model_mjcf(robot.mjcf()).ok_or_else(|| RenderError::Model("no <mujoco> element".into()))?;
        let model = MjModel::from_xml_string(&text).map_err(|e| RenderError::Model(e.to_string()))?;
        let id_of = |name: &str| {
            model
                .name_to_id(MjtObjBase::mjOBJ_JOINT, name)
                .ok_or_else(|| RenderError::Model(format!("no joint '{name}'")))
        };
        let base_qpos = model.jnt_qposadr()[id_of(flapper_sim::BASE_JOINT)?] as usize;
        let mut joint_ids = [0; N_ACTUATED_JOINTS];
        for joint in ActuatedJoint::ALL {
            joint_ids[joint.index()] = id_of(joint.name())?;
        }
        let joint_qpos = joint_ids.map(|id| model.jnt_qposadr()[id] as usize);
        let renderer = MjRenderer::builder()
            .width(width as u32)
            .height(height as u32)
            .num_visual_user_geom(MAX_DECORATIONS as u32)
            .rgb(true)
            .depth(true)
            .font_scale(MjtFontScale::mjFONTSCALE_150)
            .build(&model)
            .map_err(|e| RenderError::NoOpenGl(format!("{e:?}")))?;
        let data = MjData::try_new(Box::new(model)).map_err(|e| RenderError::Model(e.to_string()))?;
        Ok(Self {
            data,
            renderer,
            base_qpos,
            joint_ids,
            joint_qpos,
            width,
            height,
            markers: Vec::new(),
            annotated: false,
        })
    }

    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// The model's vertical field of view (deg), for framing.
    pub fn fovy_deg(&self) -> f64 {
        self.data.model().vis().global.fovy as f64
    }

    /// Spheres drawn in every following frame (replaces the previous set).
    pub fn set_markers(&mut self, markers: Vec<Marker>) -> Result<(), RenderError> {
        if markers.len() + 8 > MAX_DECORATIONS {
            return Err(RenderError::Render(format!("at most {} markers, got {}", MAX_DECORATIONS - 8, markers.len())));
        }
        self.markers = markers;
        Ok(())
    }

    /// Draws the body frame (x forward, y left, z up) and the five joints' hinge axes with their names.
    pub fn set_annotated(&mut self, annotated: bool) {
        self.annotated = annotated;
    }

    /// The robot at `pose`, seen from `camera`.
    pub fn render(&mut self, pose: &Pose, camera: &CameraView) -> Result<Frame, RenderError> {
        let qpos = self.data.qpos_mut();
        qpos[self.base_qpos..self.base_qpos + 3].copy_from_slice(&pose.position_m);
        qpos[self.base_qpos + 3..self.base_qpos + 7].copy_from_slice(&pose.orientation_wxyz);
        for (i, &adr) in self.joint_qpos.iter().enumerate() {
            qpos[adr] = pose.joint_positions_rad[i];
        }
        self.data.forward();

        let mut view = MjvCamera::new_free(self.data.model());
        view.lookat = camera.lookat_m;
        view.distance = camera.distance_m;
        view.azimuth = camera.azimuth_deg;
        view.elevation = camera.elevation_deg;
        self.renderer.set_camera(view);

        let scene = self.renderer.user_scene_mut();
        scene.clear_geom();
        for m in &self.markers {
            // SAFETY: no material, texture or object index is set (all stay -1).
            unsafe {
                scene.try_create_geom(
                    MjtGeom::mjGEOM_SPHERE,
                    Some([m.radius_m; 3]),
                    Some(m.position_m),
                    None,
                    Some(m.rgba),
                )
            }
            .map_err(|e| RenderError::Render(format!("{e:?}")))?;
        }
        if self.annotated {
            let rotation = flapper_sim::quat_from_wxyz(pose.orientation_wxyz);
            let world = |body: [f64; 3]| rotation * flapper_sim::Vec3::from_array(body);
            let p = pose.position_m;
            // Body frame: arrows from the centre, labelled at their tips.
            for (label, axis, rgba) in BODY_AXES {
                let d = world(axis);
                let to = [p[0] + 0.45 * d.x, p[1] + 0.45 * d.y, p[2] + 0.45 * d.z];
                add_connector(scene, MjtGeom::mjGEOM_ARROW, 0.012, p, to, rgba, "")?;
                add_connector(scene, MjtGeom::mjGEOM_LINE, 1.0, to, to, rgba, label)?;
            }
            // Each joint: a line from its anchor to a label placed clear of the others.
            let (anchors, axes) = (self.data.xanchor(), self.data.xaxis());
            for joint in ActuatedJoint::ALL {
                let id = self.joint_ids[joint.index()];
                let (a, axis) = (anchors[id], axes[id]);
                let ends = [0.09, -0.09].map(|h| [a[0] + h * axis[0], a[1] + h * axis[1], a[2] + h * axis[2]]);
                add_connector(scene, MjtGeom::mjGEOM_ARROW, 0.006, ends[1], ends[0], [0.0, 0.75, 0.9, 1.0], "")?;
                let d = world(JOINT_LABEL_OFFSETS_M[joint.index()]);
                let at = [a[0] + d.x, a[1] + d.y, a[2] + d.z];
                add_connector(scene, MjtGeom::mjGEOM_LINE, 1.5, a, at, [0.15, 0.15, 0.15, 1.0], "")?;
                add_connector(
                    scene,
                    MjtGeom::mjGEOM_LINE,
                    1.0,
                    at,
                    at,
                    [0.15, 0.15, 0.15, 1.0],
                    &format!("q{} {}", joint.index() + 1, joint.name()),
                )?;
            }
        }
        self.renderer.sync_data(&mut self.data).map_err(|e| RenderError::Render(format!("{e:?}")))?;
        self.renderer.render().map_err(|e| RenderError::Render(format!("{e:?}")))?;
        let rgb = self.renderer.rgb_flat().ok_or(RenderError::Render("no colour buffer".into()))?.to_vec();
        let depth_m = self.renderer.depth_flat().ok_or(RenderError::Render("no depth buffer".into()))?.to_vec();
        Ok(Frame { width: self.width, height: self.height, rgb, depth_m })
    }

    /// Several poses drawn into one picture from one camera (nearest surface wins per pixel).
    pub fn overlay(&mut self, poses: &[Pose], camera: &CameraView) -> Result<Frame, RenderError> {
        let (first, rest) = poses.split_first().ok_or(RenderError::Empty("no poses to overlay"))?;
        let mut picture = self.render(first, camera)?;
        for pose in rest {
            let frame = self.render(pose, camera)?;
            picture.merge_nearest(&frame);
        }
        Ok(picture)
    }
}
