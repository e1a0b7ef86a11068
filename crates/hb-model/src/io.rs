//! Saved models: JSON for people (coefficients keyed by term name) and compact binary (postcard
//! after a magic number and a version), in format version 4, reading versions 2 and 3 too.

use std::fmt;

use hb_basis::Basis;
use serde::de::{DeserializeOwned, MapAccess, Visitor};
use serde::ser::SerializeMap;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::error::{ModelError, ModelIoError};
use crate::form::{ModelForm, ModelFormV2, ModelFormV3};
use crate::model::{Coefficient, FitSummary, IdentifiedModel};

/// Name of the JSON format, written in every saved model.
pub const MODEL_FORMAT: &str = "hbid-model";
/// Version of the saved-model format this build writes (4: the form holds `drive_column`, the
/// record's column of a measured drive `p`, or null). It reads versions 3 (the form holds the
/// drive harmonics `drive_harmonics` and, for a list of terms, `terms`, the list of the terms'
/// names) and 2 (no drive harmonics nor term list: the clock is written with an optional whole
/// `samples_per_period` and an optional `step`) as well, in JSON and in binary.
pub const MODEL_VERSION: u32 = 4;
/// The oldest saved-model format version this build reads.
pub const MODEL_OLDEST_VERSION: u32 = 2;
/// The saved-system format version: a list of equations in the names of its coordinates and
/// drives (`crate::IdentifiedSystem`; every format version is written here, so that the
/// readers of one model and of a system tell each other's files apart).
pub const SYSTEM_VERSION: u32 = 5;
/// First bytes of a binary model.
pub const MODEL_MAGIC: [u8; 8] = *b"HBIDMODL";

/// Coefficients serialised as an ordered map `name -> {value, std_error}`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct CoefficientMap(pub(crate) Vec<Coefficient>);

#[derive(Serialize, Deserialize)]
struct Estimate {
    value: f64,
    std_error: f64,
}

impl Serialize for CoefficientMap {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for c in &self.0 {
            map.serialize_entry(
                &c.name,
                &Estimate {
                    value: c.value,
                    std_error: c.std_error,
                },
            )?;
        }
        map.end()
    }
}

impl<'de> Deserialize<'de> for CoefficientMap {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = CoefficientMap;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a map from term names to {value, std_error}")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut access: A) -> Result<CoefficientMap, A::Error> {
                let mut out = Vec::with_capacity(access.size_hint().unwrap_or(0).min(4096));
                while let Some((name, e)) = access.next_entry::<String, Estimate>()? {
                    out.push(Coefficient {
                        name,
                        value: e.value,
                        std_error: e.std_error,
                    });
                }
                Ok(CoefficientMap(out))
            }
        }
        d.deserialize_map(V)
    }
}

#[derive(Serialize, Deserialize)]
struct ModelRecord<B> {
    format: String,
    version: u32,
    basis: B,
    form: ModelForm,
    forcing_frequency: f64,
    coefficients: CoefficientMap,
    fit: Option<FitSummary>,
}

/// A model saved in binary by format version 2 (its form without drive harmonics or terms).
#[derive(Deserialize)]
struct ModelRecordV2<B> {
    format: String,
    version: u32,
    basis: B,
    form: ModelFormV2,
    forcing_frequency: f64,
    coefficients: CoefficientMap,
    fit: Option<FitSummary>,
}

/// A model saved in binary by format version 3 (its form without the measured drive's column).
#[derive(Deserialize)]
struct ModelRecordV3<B> {
    format: String,
    version: u32,
    basis: B,
    form: ModelFormV3,
    forcing_frequency: f64,
    coefficients: CoefficientMap,
    fit: Option<FitSummary>,
}

impl<B> TryFrom<ModelRecordV3<B>> for ModelRecord<B> {
    type Error = ModelError;

    fn try_from(r: ModelRecordV3<B>) -> Result<Self, ModelError> {
        Ok(Self {
            format: r.format,
            version: r.version,
            basis: r.basis,
            form: r.form.try_into()?,
            forcing_frequency: r.forcing_frequency,
            coefficients: r.coefficients,
            fit: r.fit,
        })
    }
}

impl<B> From<ModelRecordV2<B>> for ModelRecord<B> {
    fn from(r: ModelRecordV2<B>) -> Self {
        Self {
            format: r.format,
            version: r.version,
            basis: r.basis,
            form: r.form.into(),
            forcing_frequency: r.forcing_frequency,
            coefficients: r.coefficients,
            fit: r.fit,
        }
    }
}

/// Whether this build reads format `version` as one model.
fn check_version(version: u32) -> Result<(), ModelError> {
    if version == SYSTEM_VERSION {
        return Err(ModelError::Io(ModelIoError::SavedSystem));
    }
    if (MODEL_OLDEST_VERSION..=MODEL_VERSION).contains(&version) {
        Ok(())
    } else {
        Err(ModelError::Io(ModelIoError::UnsupportedVersion {
            found: version,
            supported: MODEL_VERSION,
        }))
    }
}

impl<B: Basis + Clone + Serialize> IdentifiedModel<B> {
    fn record(&self) -> ModelRecord<B> {
        ModelRecord {
            format: MODEL_FORMAT.to_owned(),
            version: MODEL_VERSION,
            basis: self.basis.clone(),
            form: self.form.clone(),
            forcing_frequency: self.forcing_frequency,
            coefficients: CoefficientMap(self.coefficients.clone()),
            fit: self.summary.clone(),
        }
    }

    /// Pretty JSON: `{"format": "hbid-model", "version": 4, "basis": .., "form": ..,
    /// "forcing_frequency": .., "coefficients": {"x'": {"value": .., "std_error": ..}, ..}, "fit": ..}`.
    ///
    /// A model on [`BasisKind`](hb_basis::BasisKind) records which basis it uses (`{"hat": {"nodes": 8}}`), so any
    /// program can load it; a model on a concrete basis type records only its size and must be
    /// loaded as the same type.
    pub fn to_json(&self) -> Result<String, ModelError> {
        Ok(serde_json::to_string_pretty(&self.record())?)
    }

    /// Compact binary: the 8 bytes [`MODEL_MAGIC`], the format version as a little-endian `u32`, then
    /// the model in postcard.
    pub fn to_bytes(&self) -> Result<Vec<u8>, ModelError> {
        let mut out = MODEL_MAGIC.to_vec();
        out.extend_from_slice(&MODEL_VERSION.to_le_bytes());
        Ok(postcard::to_extend(&self.record(), out)?)
    }
}

impl<B: Basis + DeserializeOwned> IdentifiedModel<B> {
    fn from_record(r: ModelRecord<B>) -> Result<Self, ModelError> {
        check_version(r.version)?;
        if r.format != MODEL_FORMAT {
            return Err(ModelError::Io(ModelIoError::BadMagic));
        }
        if let Some(fit) = &r.fit {
            for (name, v) in [
                ("fit condition", fit.condition),
                ("fit residual_rms", fit.residual_rms),
                ("fit residual_variance", fit.residual_variance),
            ] {
                // The condition number may legitimately be infinite only for a rank-deficient
                // system, which never becomes a model.
                if !v.is_finite() {
                    return Err(ModelError::Io(ModelIoError::NonFiniteModelValue {
                        name: name.to_owned(),
                    }));
                }
            }
        }
        Self::from_coefficients(
            r.basis,
            r.form.validate()?,
            r.forcing_frequency,
            r.coefficients.0,
            r.fit,
        )
    }

    /// Reads a model written by [`to_json`](Self::to_json), checking that its terms match its basis
    /// and form.
    pub fn from_json(text: &str) -> Result<Self, ModelError> {
        #[derive(Deserialize)]
        struct Version {
            version: u32,
        }
        if let Ok(v) = serde_json::from_str::<Version>(text) {
            check_version(v.version)?;
        }
        Self::from_record(serde_json::from_str(text)?)
    }

    /// Reads a model written by [`to_bytes`](Self::to_bytes).
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, ModelError> {
        if bytes.len() < 12 || bytes[..8] != MODEL_MAGIC {
            return Err(ModelError::Io(ModelIoError::BadMagic));
        }
        let version = u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]);
        check_version(version)?;
        let record: ModelRecord<B> = match version {
            2 => postcard::from_bytes::<ModelRecordV2<B>>(&bytes[12..])?.into(),
            3 => postcard::from_bytes::<ModelRecordV3<B>>(&bytes[12..])?.try_into()?,
            _ => postcard::from_bytes(&bytes[12..])?,
        };
        if record.version != version {
            return Err(ModelError::Io(ModelIoError::UnsupportedVersion {
                found: record.version,
                supported: MODEL_VERSION,
            }));
        }
        Self::from_record(record)
    }
}
