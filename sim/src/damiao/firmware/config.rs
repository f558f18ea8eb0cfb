//! How one motor is configured (ids, model, rig, temperatures) and what it keeps in flash.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::damiao::model::Model;
use crate::damiao::registers::{rid, RegisterFile};
use crate::robstride::rig::Load;
use crate::state_file::InvalidField;

/// The highest 11-bit identifier, and so the highest ESC_ID or MST_ID (registers 7 and 8).
pub const MAX_ID: u16 = 0x7FF;

/// The OpenArm's feedback-id convention: MST_ID = ESC_ID + 0x10 (J1 sends on 0x01 and answers
/// on 0x11, …, J8 0x08/0x18; note §10).
pub const OPENARM_MST_OFFSET: u16 = 0x10;

/// What a motor keeps across power cycles: the read-write registers as the last save (0xAA)
/// found them, by name, and the zero the last `FE` set.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PersistedMotor {
    /// Read-write registers by name ([`crate::damiao::registers::TABLE`]); u32 registers as
    /// whole numbers.
    pub registers: BTreeMap<String, f64>,
    /// The plant angle that reads 0 (rad).
    pub zero_offset_rad: f64,
}

impl PersistedMotor {
    /// Read what [`crate::actuator::ActuatorFirmware::persisted`] wrote for a `model` motor,
    /// every value checked as the command that stores it would check it.
    pub fn from_value(model: Model, value: &serde_json::Value) -> Result<Self, InvalidField> {
        let persisted = Self::deserialize(value)
            .map_err(|e| InvalidField::new("flash", format!("not a Damiao flash image: {e}")))?;
        persisted.validate(model)?;
        Ok(persisted)
    }

    /// Check every register (as a 0x55 write would) and the zero (finite).
    pub fn validate(&self, model: Model) -> Result<(), InvalidField> {
        let mut file = RegisterFile::defaults(model, 0, 0, 0);
        file.apply_saved(&self.registers, "flash.registers")?;
        if !self.zero_offset_rad.is_finite() {
            return Err(InvalidField::new(
                "flash.zero_offset_rad",
                "not a finite angle",
            ));
        }
        Ok(())
    }

    /// A saved id register (ESC_ID, MST_ID), if the image holds one.
    fn id(&self, name: &str) -> Option<u16> {
        let x = *self.registers.get(name)?;
        // Validated within 0..=0x7FF and whole: the cast is exact.
        (x.fract() == 0.0 && (0.0..=f64::from(MAX_ID)).contains(&x)).then_some(x as u16)
    }
}

/// Configuration of one emulated motor.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MotorConfig {
    /// Command id (ESC_ID, register 8) at first power-on; a flash image may hold another.
    pub esc_id: u16,
    /// Feedback id (MST_ID, register 7) at first power-on.
    pub mst_id: u16,
    /// Model.
    pub model: Model,
    /// What the motor drives on the built-in rig.
    pub load: Load,
    /// Viscous friction of the rig (N·m·s/rad).
    pub friction_nm_s_per_rad: f64,
    /// Shaft angle at power-on (rad).
    pub start_angle_rad: f64,
    /// Ambient temperature (°C): the board and coil start here and return here when a
    /// temperature fault is cleared.
    pub ambient_c: f64,
    /// Serial number (register 15); derived from the model and first ESC_ID when `None`.
    pub serial_number: Option<u32>,
    /// What the motor saved in an earlier run, applied at power-on.
    pub flash: Option<PersistedMotor>,
}

impl MotorConfig {
    /// A motor on `esc_id` answering on `esc_id + 0x10` (the OpenArm convention, wrapped into
    /// 11 bits), driving the default rig (1 kg, 0.1 m disc) at 25 °C.
    pub fn new(esc_id: u16, model: Model) -> Self {
        Self {
            esc_id,
            mst_id: esc_id.wrapping_add(OPENARM_MST_OFFSET) & MAX_ID,
            model,
            load: Load::default(),
            friction_nm_s_per_rad: 0.0,
            start_angle_rad: 0.0,
            ambient_c: 25.0,
            serial_number: None,
            flash: None,
        }
    }

    /// The same motor with another load.
    pub fn with_load(mut self, load: Load) -> Self {
        self.load = load;
        self
    }

    /// The same motor answering on `mst_id`.
    pub fn with_mst_id(mut self, mst_id: u16) -> Self {
        self.mst_id = mst_id;
        self
    }

    /// A `model` motor powering on from a flash image ([`crate::actuator::ActuatorFirmware::
    /// persisted`]'s JSON): its ids are the image's (ESC_ID required; MST_ID defaulting to the
    /// OpenArm convention), every value checked.
    pub fn from_persisted(model: Model, value: &serde_json::Value) -> Result<Self, InvalidField> {
        let flash = PersistedMotor::from_value(model, value)?;
        let esc_id = flash
            .id("ESC_ID")
            .ok_or_else(|| InvalidField::new("flash.registers.ESC_ID", "missing"))?;
        let mut config = Self::new(esc_id, model);
        if let Some(mst_id) = flash.id("MST_ID") {
            config.mst_id = mst_id;
        }
        config.flash = Some(flash);
        Ok(config)
    }

    /// Check the ids (11 bits), the temperatures and angle (finite) and the flash image.
    pub fn validate(&self) -> Result<(), InvalidField> {
        for (field, id) in [("esc_id", self.esc_id), ("mst_id", self.mst_id)] {
            if id > MAX_ID {
                return Err(InvalidField::new(
                    field,
                    format!("0x{id:X} is not an 11-bit identifier (0..=0x7FF)"),
                ));
            }
        }
        for (field, x) in [
            ("start_angle_rad", self.start_angle_rad),
            ("ambient_c", self.ambient_c),
            ("friction_nm_s_per_rad", self.friction_nm_s_per_rad),
        ] {
            if !x.is_finite() {
                return Err(InvalidField::new(field, "not a finite number"));
            }
        }
        if let Some(flash) = &self.flash {
            flash.validate(self.model)?;
        }
        Ok(())
    }

    /// The serial number register 15 holds: the configured one, or one derived from the model
    /// and first ESC_ID (stable across runs, distinct per motor).
    pub fn effective_serial(&self) -> u32 {
        self.serial_number.unwrap_or_else(|| {
            // FNV-1a over (model name, ESC_ID), folded to 32 bits.
            let mut hash: u32 = 0x811C_9DC5;
            for byte in self.model.name().bytes().chain(self.esc_id.to_le_bytes()) {
                hash ^= u32::from(byte);
                hash = hash.wrapping_mul(0x0100_0193);
            }
            hash
        })
    }

    /// The registers at power-on: the model's defaults with this motor's ids and serial, then
    /// the flash image (an image that fails its check is left out, with an error logged:
    /// [`MotorConfig::validate`] is where a caller learns of it).
    pub(crate) fn power_on_registers(&self) -> RegisterFile {
        let mut registers = RegisterFile::defaults(
            self.model,
            self.esc_id & MAX_ID,
            self.mst_id & MAX_ID,
            self.effective_serial(),
        );
        if let Some(flash) = &self.flash {
            let mut restored = registers.clone();
            match restored.apply_saved(&flash.registers, "flash.registers") {
                Ok(()) => registers = restored,
                Err(error) => {
                    tracing::error!(%error, esc_id = self.esc_id, "damiao: flash image refused, using defaults");
                }
            }
        }
        debug_assert!(registers.number(rid::ESC_ID) <= f64::from(MAX_ID));
        registers
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn new_follows_the_openarm_id_convention() {
        let config = MotorConfig::new(0x03, Model::DM4340);
        assert_eq!((config.esc_id, config.mst_id), (0x03, 0x13));
        assert_eq!(MotorConfig::new(0x7F8, Model::DM4310).mst_id, 0x008);
        assert!(config.validate().is_ok());
        assert!(MotorConfig::new(0x800, Model::DM4310).validate().is_err());
        assert_ne!(
            config.effective_serial(),
            MotorConfig::new(0x04, Model::DM4340).effective_serial()
        );
    }

    #[test]
    fn a_flash_image_gives_its_ids_and_is_checked() {
        let image = serde_json::json!({
            "registers": {"ESC_ID": 5.0, "MST_ID": 0x25, "TIMEOUT": 200.0},
            "zero_offset_rad": 0.25
        });
        let config = MotorConfig::from_persisted(Model::DM4310, &image).unwrap();
        assert_eq!((config.esc_id, config.mst_id), (5, 0x25));
        assert_eq!(config.power_on_registers().number(rid::TIMEOUT), 200.0);
        let bad = serde_json::json!({"registers": {"CTRL_MODE": 9.0}, "zero_offset_rad": 0.0});
        let error = PersistedMotor::from_value(Model::DM4310, &bad).unwrap_err();
        assert_eq!(error.field, "flash.registers.CTRL_MODE");
        let no_id = serde_json::json!({"registers": {}, "zero_offset_rad": 0.0});
        assert!(MotorConfig::from_persisted(Model::DM4310, &no_id).is_err());
        let extra = serde_json::json!({"registers": {}, "zero_offset_rad": 0.0, "x": 1});
        assert!(PersistedMotor::from_value(Model::DM4310, &extra).is_err());
    }
}
