//! The numbers the controller takes from the arm model, in one place (so the rest of the
//! controller does not depend on how [`ArmModel`] stores them).

use super::model::ArmModel;

/// One modified-DH row as the controller reports it (`get_DH_data`).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DhRow {
    /// Link twist alpha(i-1), degrees.
    pub alpha_deg: f64,
    /// Link length a(i-1), m.
    pub a_m: f64,
    /// Link offset d(i), m.
    pub d_m: f64,
    /// Joint angle offset, degrees.
    pub offset_deg: f64,
}

/// Model facts used by the controller.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelFacts {
    /// Product name reported as `Product_version` ("RM65-B").
    pub product: String,
    /// Number of joints.
    pub dof: usize,
    /// Lower joint limits, degrees.
    pub min_deg: Vec<f64>,
    /// Upper joint limits, degrees.
    pub max_deg: Vec<f64>,
    /// Joint speed limits, °/s.
    pub max_speed_deg_s: Vec<f64>,
    /// Joint acceleration limits, °/s².
    pub max_acc_deg_s2: Vec<f64>,
    /// MDH table.
    pub dh: Vec<DhRow>,
}

impl ModelFacts {
    /// Read the facts out of a model.
    pub fn of(model: &ArmModel) -> Self {
        let last = model.mdh.len().saturating_sub(1);
        let dh = model
            .mdh
            .iter()
            .enumerate()
            .map(|(i, r)| DhRow {
                alpha_deg: r.alpha_rad.to_degrees(),
                a_m: r.a_m,
                // The model keeps the flange distance apart; the controller reports it as the
                // last row's d.
                d_m: if i == last {
                    r.d_m + model.flange_d_m
                } else {
                    r.d_m
                },
                offset_deg: r.offset_rad.to_degrees(),
            })
            .collect();
        Self {
            product: model.name.clone(),
            dof: model.dof,
            min_deg: model.joint_min_deg.clone(),
            max_deg: model.joint_max_deg.clone(),
            max_speed_deg_s: model.max_speed_deg_s.clone(),
            max_acc_deg_s2: model.max_acc_deg_s2.clone(),
            dh,
        }
    }
}
