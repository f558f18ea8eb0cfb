//! The few pieces of spatial (6D) algebra the articulated-body solver needs, in Featherstone's
//! conventions: a motion vector is `[ω; v]`, a force vector `[n; f]`, both in a body's own
//! coordinates about its origin.

use nalgebra::{Isometry3, Matrix3, Matrix6, Vector3, Vector6};

use super::super::LinkInertial;

/// The transform of motion vectors from a parent frame to a child frame whose pose in the
/// parent is `child_in_parent` (`x_parent = R · x_child + p`). Its transpose carries force
/// vectors from the child back to the parent.
pub(super) fn motion_transform(child_in_parent: &Isometry3<f64>) -> Matrix6<f64> {
    let e = child_in_parent
        .rotation
        .to_rotation_matrix()
        .into_inner()
        .transpose();
    let p = child_in_parent.translation.vector;
    let mut x = Matrix6::zeros();
    x.fixed_view_mut::<3, 3>(0, 0).copy_from(&e);
    x.fixed_view_mut::<3, 3>(3, 3).copy_from(&e);
    x.fixed_view_mut::<3, 3>(3, 0)
        .copy_from(&(-e * p.cross_matrix()));
    x
}

/// The angular part of a spatial vector.
pub(super) fn angular(v: &Vector6<f64>) -> Vector3<f64> {
    Vector3::new(v[0], v[1], v[2])
}

/// The linear part of a spatial vector.
pub(super) fn linear(v: &Vector6<f64>) -> Vector3<f64> {
    Vector3::new(v[3], v[4], v[5])
}

/// A spatial vector from its angular and linear parts.
pub(super) fn spatial(angular: Vector3<f64>, linear: Vector3<f64>) -> Vector6<f64> {
    Vector6::new(
        angular.x, angular.y, angular.z, linear.x, linear.y, linear.z,
    )
}

/// `v ×m m`: the cross product of two motion vectors.
pub(super) fn cross_motion(v: &Vector6<f64>, m: &Vector6<f64>) -> Vector6<f64> {
    let (w, vl) = (angular(v), linear(v));
    let (mw, ml) = (angular(m), linear(m));
    spatial(w.cross(&mw), w.cross(&ml) + vl.cross(&mw))
}

/// `v ×* f`: the cross product of a motion vector and a force vector.
pub(super) fn cross_force(v: &Vector6<f64>, f: &Vector6<f64>) -> Vector6<f64> {
    let (w, vl) = (angular(v), linear(v));
    let (n, fl) = (angular(f), linear(f));
    spatial(w.cross(&n) + vl.cross(&fl), w.cross(&fl))
}

/// The spatial inertia of a link about its frame's origin, in its frame's axes.
pub(super) fn spatial_inertia(inertial: &LinkInertial) -> Matrix6<f64> {
    let m = inertial.mass_kg;
    let cx: Matrix3<f64> = inertial.com_m.cross_matrix();
    let mut i = Matrix6::zeros();
    i.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(inertial.inertia_kg_m2 + cx * cx.transpose() * m));
    i.fixed_view_mut::<3, 3>(0, 3).copy_from(&(cx * m));
    i.fixed_view_mut::<3, 3>(3, 0)
        .copy_from(&(cx.transpose() * m));
    i.fixed_view_mut::<3, 3>(3, 3)
        .copy_from(&(Matrix3::identity() * m));
    i
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion};

    #[test]
    fn a_transform_moves_a_velocity_to_the_child_frame() {
        // Child 1 m along the parent's x, turned 90° about z. The parent spins at 1 rad/s
        // about its z: the child's origin moves at 1 m/s along the parent's y, which is the
        // child's x.
        let t = Isometry3::from_parts(
            Translation3::new(1.0, 0.0, 0.0),
            UnitQuaternion::from_euler_angles(0.0, 0.0, std::f64::consts::FRAC_PI_2),
        );
        let v = motion_transform(&t) * spatial(Vector3::z(), Vector3::zeros());
        assert!((angular(&v) - Vector3::z()).norm() < 1e-12);
        assert!(
            (linear(&v) - Vector3::new(1.0, 0.0, 0.0)).norm() < 1e-12,
            "{v}"
        );
    }

    #[test]
    fn spatial_inertia_gives_the_kinetic_energy_of_a_point_mass() {
        let inertial = LinkInertial {
            mass_kg: 2.0,
            com_m: Vector3::new(0.5, 0.0, 0.0),
            inertia_kg_m2: Matrix3::zeros(),
        };
        // Spinning at 3 rad/s about the frame's z: the mass moves at 1.5 m/s.
        let v = spatial(Vector3::z() * 3.0, Vector3::zeros());
        let energy = 0.5 * v.dot(&(spatial_inertia(&inertial) * v));
        assert!((energy - 0.5 * 2.0 * 1.5 * 1.5).abs() < 1e-12);
    }
}
