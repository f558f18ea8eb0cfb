//! The emulator's own JSON codec: replies written in the controller's key order, request
//! fields read leniently, and the wire integer units (docs/protocols/realman.md §2).
//!
//! Replies are built by hand rather than through `serde_json::Value` because the controller's
//! key order (`"command"`/`"state"` first) is part of what clients and transcripts see, and
//! `serde_json`'s map sorts keys.

use serde_json::Value;

use super::kinematics::Pose;

/// A compact JSON object under construction, keys kept in insertion order.
#[derive(Debug, Clone, Default)]
pub struct Obj {
    text: String,
}

impl Obj {
    /// An empty object.
    pub fn new() -> Self {
        Self {
            text: String::from("{"),
        }
    }

    /// `{"command":name}` — the start of a set-type reply.
    pub fn command(name: &str) -> Self {
        Self::new().str("command", name)
    }

    /// `{"state":tag}` — the start of a query reply or event.
    pub fn state(tag: &str) -> Self {
        Self::new().str("state", tag)
    }

    fn key(mut self, key: &str) -> Self {
        if self.text.len() > 1 {
            self.text.push(',');
        }
        push_string(&mut self.text, key);
        self.text.push(':');
        self
    }

    /// A string member.
    pub fn str(self, key: &str, value: &str) -> Self {
        let mut o = self.key(key);
        push_string(&mut o.text, value);
        o
    }

    /// An integer member.
    pub fn int(self, key: &str, value: i64) -> Self {
        let mut o = self.key(key);
        o.text.push_str(&value.to_string());
        o
    }

    /// A boolean member.
    pub fn bool(self, key: &str, value: bool) -> Self {
        let mut o = self.key(key);
        o.text.push_str(if value { "true" } else { "false" });
        o
    }

    /// An integer-array member.
    pub fn ints(self, key: &str, values: &[i64]) -> Self {
        let mut o = self.key(key);
        push_ints(&mut o.text, values);
        o
    }

    /// A string-array member.
    pub fn strs(self, key: &str, values: &[&str]) -> Self {
        let mut o = self.key(key);
        o.text.push('[');
        for (i, v) in values.iter().enumerate() {
            if i > 0 {
                o.text.push(',');
            }
            push_string(&mut o.text, v);
        }
        o.text.push(']');
        o
    }

    /// A nested object member.
    pub fn obj(self, key: &str, value: Obj) -> Self {
        let mut o = self.key(key);
        o.text.push_str(&value.finish());
        o
    }

    /// The object's text (compact, no terminator).
    pub fn finish(mut self) -> String {
        self.text.push('}');
        self.text
    }
}

fn push_string(out: &mut String, s: &str) {
    // serde_json's string escaping cannot fail for a &str.
    out.push_str(&serde_json::to_string(s).unwrap_or_else(|_| String::from("\"\"")));
}

fn push_ints(out: &mut String, values: &[i64]) {
    out.push('[');
    for (i, v) in values.iter().enumerate() {
        if i > 0 {
            out.push(',');
        }
        out.push_str(&v.to_string());
    }
    out.push(']');
}

/// `{"command":name,key:ok}` — the common set-type acknowledgement.
pub fn ack(name: &str, key: &str, ok: bool) -> String {
    Obj::command(name).bool(key, ok).finish()
}

/// Angle in rad → wire 0.001°.
pub fn rad_to_mdeg(rad: f64) -> i64 {
    round(rad.to_degrees() * 1000.0)
}

/// Wire 0.001° → rad.
pub fn mdeg_to_rad(mdeg: i64) -> f64 {
    (mdeg as f64 / 1000.0).to_radians()
}

/// Length in m → wire 1e-6 m.
pub fn m_to_um(m: f64) -> i64 {
    round(m * 1e6)
}

/// A value scaled by 1000 (rad → 0.001 rad, m/s → 0.001 m/s, °C → 0.001 °C, …).
pub fn milli(value: f64) -> i64 {
    round(value * 1000.0)
}

/// Round to the nearest wire integer; non-finite values become 0 rather than garbage.
fn round(value: f64) -> i64 {
    if value.is_finite() {
        value.round().clamp(i64::MIN as f64, i64::MAX as f64) as i64
    } else {
        0
    }
}

/// Pose → wire `[x,y,z (1e-6 m), rx,ry,rz (0.001 rad)]`.
pub fn pose_to_wire(pose: &Pose) -> [i64; 6] {
    let p = pose.position_m;
    let e = pose.euler_rad;
    [
        m_to_um(p[0]),
        m_to_um(p[1]),
        m_to_um(p[2]),
        milli(e[0]),
        milli(e[1]),
        milli(e[2]),
    ]
}

/// Wire pose `[x,y,z (1e-6 m), rx,ry,rz (0.001 rad)]` → Pose.
pub fn pose_from_wire(w: &[i64]) -> Option<Pose> {
    if w.len() != 6 {
        return None;
    }
    Some(Pose {
        position_m: [w[0] as f64 * 1e-6, w[1] as f64 * 1e-6, w[2] as f64 * 1e-6],
        euler_rad: [w[3] as f64 * 1e-3, w[4] as f64 * 1e-3, w[5] as f64 * 1e-3],
    })
}

/// Wire `pose_quat` `[x,y,z (1e-6 m), w,x,y,z (1e-6)]` → Pose (Z-Y-X Euler from the quaternion).
pub fn pose_from_quat_wire(w: &[i64]) -> Option<Pose> {
    if w.len() != 7 {
        return None;
    }
    let q: Vec<f64> = w[3..].iter().map(|v| *v as f64 * 1e-6).collect();
    let norm = q.iter().map(|c| c * c).sum::<f64>().sqrt();
    if norm < 1e-9 {
        return None;
    }
    let (qw, qx, qy, qz) = (q[0] / norm, q[1] / norm, q[2] / norm, q[3] / norm);
    let rx = (2.0 * (qw * qx + qy * qz)).atan2(1.0 - 2.0 * (qx * qx + qy * qy));
    let ry = (2.0 * (qw * qy - qz * qx)).clamp(-1.0, 1.0).asin();
    let rz = (2.0 * (qw * qz + qx * qy)).atan2(1.0 - 2.0 * (qy * qy + qz * qz));
    Some(Pose {
        position_m: [w[0] as f64 * 1e-6, w[1] as f64 * 1e-6, w[2] as f64 * 1e-6],
        euler_rad: [rx, ry, rz],
    })
}

/// Lenient field access on a request object.
#[derive(Debug, Clone, Copy)]
pub struct Req<'a>(pub &'a Value);

impl<'a> Req<'a> {
    /// The `command` name, if it is a string.
    pub fn command(&self) -> Option<&'a str> {
        self.0.get("command")?.as_str()
    }

    /// An integer field (floats are truncated toward zero, as a C client's cast would).
    pub fn int(&self, key: &str) -> Option<i64> {
        int_of(self.0.get(key)?)
    }

    /// A boolean field; 0/1 integers count as booleans.
    pub fn bool(&self, key: &str) -> Option<bool> {
        match self.0.get(key)? {
            Value::Bool(b) => Some(*b),
            v => int_of(v).map(|i| i != 0),
        }
    }

    /// A string field.
    pub fn str(&self, key: &str) -> Option<&'a str> {
        self.0.get(key)?.as_str()
    }

    /// An integer-array field (every element must be a number).
    pub fn ints(&self, key: &str) -> Option<Vec<i64>> {
        ints_of(self.0.get(key)?)
    }

    /// A nested object field.
    pub fn sub(&self, key: &str) -> Option<Req<'a>> {
        let v = self.0.get(key)?;
        v.is_object().then_some(Req(v))
    }
}

fn int_of(v: &Value) -> Option<i64> {
    v.as_i64().or_else(|| {
        v.as_f64()
            .filter(|f| f.is_finite() && f.abs() < 9.0e15)
            .map(|f| f as i64)
    })
}

/// An array of integers.
pub fn ints_of(v: &Value) -> Option<Vec<i64>> {
    v.as_array()?.iter().map(int_of).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn objects_keep_key_order_and_escape_strings() {
        let text = Obj::state("joint_degree")
            .ints("joint", &[1, -2])
            .str("name", "a\"b")
            .bool("ok", true)
            .obj("sub", Obj::new().int("x", 3))
            .finish();
        assert_eq!(
            text,
            r#"{"state":"joint_degree","joint":[1,-2],"name":"a\"b","ok":true,"sub":{"x":3}}"#
        );
    }

    #[test]
    fn unit_conversions_round_trip() {
        assert_eq!(rad_to_mdeg(10.1f64.to_radians()), 10100);
        assert!((mdeg_to_rad(10100) - 10.1f64.to_radians()).abs() < 1e-12);
        assert_eq!(m_to_um(0.1), 100000);
        assert_eq!(milli(f64::NAN), 0);
    }

    #[test]
    fn quaternion_pose_matches_euler() {
        // 90° about Z: w = cos 45°, z = sin 45°.
        let p = pose_from_quat_wire(&[0, 0, 100000, 707107, 0, 0, 707107]).unwrap();
        assert!((p.euler_rad[2] - std::f64::consts::FRAC_PI_2).abs() < 1e-5);
        assert!((p.position_m[2] - 0.1).abs() < 1e-12);
    }
}
