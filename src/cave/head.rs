use glam::{DQuat, DVec3};

/// The rig's convention for a head at rest: which way it looks and which
/// way is up, in rig coordinates. Yaw turns about `up`, pitch about
/// `right`, roll about `forward`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeadFrame {
    pub forward: DVec3,
    pub up: DVec3,
    pub right: DVec3,
}

impl HeadFrame {
    /// Orthonormal frame from a forward and a roughly-up vector; `None` if
    /// either is zero or they are parallel.
    pub fn new(forward: DVec3, up: DVec3) -> Option<Self> {
        let forward = forward.try_normalize()?;
        let right = forward.cross(up).try_normalize()?;
        Some(Self {
            forward,
            up: right.cross(forward),
            right,
        })
    }

    /// Rotation for yaw, pitch and roll in degrees: positive yaw turns left,
    /// positive pitch looks up, positive roll tilts the head to the right.
    pub fn orientation(&self, ypr_degrees: DVec3) -> DQuat {
        let [yaw, pitch, roll] = ypr_degrees.to_array().map(f64::to_radians);
        DQuat::from_axis_angle(self.up, yaw)
            * DQuat::from_axis_angle(self.right, pitch)
            * DQuat::from_axis_angle(self.forward, roll)
    }
}

/// Where the midpoint between the eyes sits relative to the neck's pivot,
/// in metres as (right, up, forward) in the head frame: the neck model of
/// head-mounted display runtimes (the Oculus SDK's defaults), with which a
/// turning head moves its eyes as a real one does.
pub const NECK_TO_EYES_M: DVec3 = DVec3::new(0.0, 0.075, 0.0805);

/// A tracked head: position in rig units and orientation relative to the
/// rig's [`HeadFrame`] at rest.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeadPose {
    pub position: DVec3,
    pub orientation: DQuat,
}

/// One timed pose of a head path (seconds from the path's start).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathKey {
    pub time: f64,
    pub pose: HeadPose,
}

/// The pose at `time` along keys sorted by time: linear in position,
/// spherical in orientation, held constant before the first and after the
/// last key. `None` for an empty path.
pub fn pose_along(keys: &[PathKey], time: f64) -> Option<HeadPose> {
    let first = keys.first()?;
    let last = keys.last()?;
    if time <= first.time {
        return Some(first.pose);
    }
    if time >= last.time {
        return Some(last.pose);
    }
    let i = keys.partition_point(|k| k.time <= time);
    let (a, b) = (&keys[i - 1], &keys[i]);
    let s = (time - a.time) / (b.time - a.time);
    Some(HeadPose {
        position: a.pose.position.lerp(b.pose.position, s),
        orientation: a.pose.orientation.slerp(b.pose.orientation, s),
    })
}
