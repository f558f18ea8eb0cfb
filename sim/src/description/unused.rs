//! What a URDF says that armhil does not use, said once at start instead of ignored silently.

use std::collections::BTreeMap;

use super::Description;

/// Elements directly under `<robot>` that the physics reads.
const ROBOT_CHILDREN_USED: [&str; 3] = ["link", "joint", "material"];
/// Elements of a `<joint>` that the physics reads.
const JOINT_CHILDREN_USED: [&str; 7] = [
    "origin", "parent", "child", "axis", "limit", "dynamics", "mimic",
];

impl Description {
    /// One line listing what the URDF holds that is not simulated (`<transmission>`,
    /// `<gazebo>`, a joint's `<safety_controller>` …), with counts;
    /// `None` when everything is used.
    pub fn unused_summary(&self) -> Option<String> {
        let Ok(doc) = roxmltree::Document::parse(self.text()) else {
            return None;
        };
        let mut counts: BTreeMap<String, usize> = BTreeMap::new();
        for node in doc.root_element().children().filter(|n| n.is_element()) {
            let tag = node.tag_name().name();
            if !ROBOT_CHILDREN_USED.contains(&tag) {
                *counts.entry(format!("<{tag}>")).or_default() += 1;
                continue;
            }
            if tag != "joint" {
                continue;
            }
            for child in node.children().filter(|n| n.is_element()) {
                let name = child.tag_name().name();
                if !JOINT_CHILDREN_USED.contains(&name) {
                    *counts.entry(format!("<joint><{name}>")).or_default() += 1;
                }
            }
        }
        if counts.is_empty() {
            return None;
        }
        let list: Vec<String> = counts
            .iter()
            .map(|(what, n)| format!("{n} {what}"))
            .collect();
        Some(format!("not simulated: {}", list.join(", ")))
    }
}
