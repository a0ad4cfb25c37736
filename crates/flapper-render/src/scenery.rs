//! The render model: the robot's own MJCF with visual-only scenery added (a sky, a ground grid at
//! z = 0 without contacts, the offscreen buffer size, far clipping for long flights). It is only
//! ever posed and drawn, never stepped, so nothing here can change a flight.

/// Offscreen buffer size the renderer may use (pixels); frames are at most this big.
pub const MAX_WIDTH_PX: usize = 1920;
pub const MAX_HEIGHT_PX: usize = 1080;

const SCENERY: &str = r#"
  <!-- flapper-render: visual-only scenery -->
  <visual>
    <global offwidth="1920" offheight="1080"/>
    <map znear="0.01" zfar="400"/>
    <quality shadowsize="1024"/>
    <headlight ambient="0.35 0.35 0.35" diffuse="0.5 0.5 0.5"/>
    <scale jointlength="1.2" jointwidth="0.06"/>
  </visual>
  <asset>
    <texture name="flapper_render_sky" type="skybox" builtin="gradient" rgb1="0.52 0.7 0.9" rgb2="0.93 0.96 1" width="512" height="3072"/>
    <texture name="flapper_render_grid" type="2d" builtin="checker" rgb1="0.45 0.58 0.38" rgb2="0.41 0.53 0.35" width="512" height="512" mark="edge" markrgb="0.8 0.85 0.75"/>
    <material name="flapper_render_grid" texture="flapper_render_grid" texrepeat="1 1" texuniform="true" reflectance="0"/>
  </asset>
  <worldbody>
    <geom name="flapper_render_ground" type="plane" size="0 0 1" material="flapper_render_grid" contype="0" conaffinity="0"/>
  </worldbody>
"#;

/// The robot's MJCF with the scenery inserted right after the opening `<mujoco ...>` tag.
pub fn render_model_mjcf(robot_mjcf: &str) -> Option<String> {
    let start = robot_mjcf.find("<mujoco")?;
    let end = start + robot_mjcf[start..].find('>')? + 1;
    Some(format!("{}{SCENERY}{}", &robot_mjcf[..end], &robot_mjcf[end..]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scenery_adds_a_ground_and_keeps_the_robot() {
        let robot = flapper_sim::RobotModel::flapper().unwrap();
        let text = render_model_mjcf(robot.mjcf()).unwrap();
        let scene = mujoco_rs::prelude::MjModel::from_xml_string(&text).unwrap();
        let nominal = robot.mujoco();
        assert_eq!(scene.ffi().ngeom, nominal.ffi().ngeom + 1);
        assert_eq!(scene.ffi().nq, nominal.ffi().nq);
        assert_eq!(scene.body_mass(), nominal.body_mass());
        assert!(render_model_mjcf("<notmujoco/>").is_none());
    }
}
