//! The records of a stand config with several units (`[[unit]]` tables): every record of a unit
//! carries `"unit": NAME` (CONTRACT.md), and the channel's measurement unit, which `unit` holds
//! in a one-unit run, moves to `"channel_unit"` (docs/records.md, "Several units").
//!
//! The writer wraps a record in a [`UnitRecord`], which writes the record's own fields in their
//! order with `unit` right after `type`; readers call [`untag`] on each JSON object to get the
//! unit's name back and the record in its one-unit shape, so every reader of records (plot,
//! report, table, export, aggregate, limits) reads both shapes with the same code.

use serde::de::{MapAccess, Visitor};
use serde::ser::{Error as _, SerializeMap};
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use serde_json::value::RawValue;
use serde_json::Value;

/// The key of the unit's name in records of several units.
pub const UNIT_KEY: &str = "unit";

/// Where a record of several units keeps its channel's measurement unit.
pub const CHANNEL_UNIT_KEY: &str = "channel_unit";

/// A record of one named unit, as written: `{"type": ..., "unit": NAME, ...the record's fields,
/// its `unit` as `channel_unit`}`.
#[derive(Debug, Clone, Copy)]
pub struct UnitRecord<'a, R: Serialize> {
    /// The unit's name (`unit[i].name` of the stand config).
    pub unit: &'a str,
    pub record: &'a R,
}

/// A JSON object's fields in the order they were written, values untouched.
struct Ordered(Vec<(String, Box<RawValue>)>);

impl<'de> Deserialize<'de> for Ordered {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Ordered;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a JSON object")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut m: A) -> Result<Ordered, A::Error> {
                let mut fields = Vec::new();
                while let Some((k, v)) = m.next_entry::<String, Box<RawValue>>()? {
                    fields.push((k, v));
                }
                Ok(Ordered(fields))
            }
        }
        d.deserialize_map(V)
    }
}

impl<R: Serialize> Serialize for UnitRecord<'_, R> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let text = serde_json::to_string(self.record).map_err(S::Error::custom)?;
        let fields: Ordered = serde_json::from_str(&text).map_err(S::Error::custom)?;
        let mut m = s.serialize_map(Some(fields.0.len() + 1))?;
        let mut named = false;
        for (k, v) in &fields.0 {
            if k == UNIT_KEY {
                m.serialize_entry(CHANNEL_UNIT_KEY, v)?;
            } else {
                m.serialize_entry(k, v)?;
            }
            if k == "type" && !named {
                m.serialize_entry(UNIT_KEY, self.unit)?;
                named = true;
            }
        }
        if !named {
            m.serialize_entry(UNIT_KEY, self.unit)?;
        }
        m.end()
    }
}

/// Record types that have no channel unit of their own: in them `unit` is always the unit's
/// name (written only by a run of several units).
const UNIT_WIDE: [&str; 3] = ["health", "summary", "outage"];

/// Undoes [`UnitRecord`] on a record read back: returns the unit's name and leaves the record
/// as a one-unit run writes it (`channel_unit` back in `unit`, or no `unit` where the type has
/// none). `None` for a record of a one-unit run (left as it is).
pub fn untag(v: &mut Value) -> Option<String> {
    let obj = v.as_object_mut()?;
    if let Some(cu) = obj.remove(CHANNEL_UNIT_KEY) {
        let name = obj.insert(UNIT_KEY.into(), cu)?;
        return name.as_str().map(String::from);
    }
    let kind = obj.get("type").and_then(Value::as_str)?;
    if UNIT_WIDE.contains(&kind) {
        if let Some(Value::String(_)) = obj.get(UNIT_KEY) {
            return match obj.remove(UNIT_KEY) {
                Some(Value::String(n)) => Some(n),
                _ => None,
            };
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sink::records::HealthRecord;

    /// A curve record of a named unit: `unit` follows `type`, the channel's unit is in
    /// `channel_unit`, every other field in its place; `untag` gives back the one-unit line.
    #[test]
    fn curve_round_trip() {
        let one =
            serde_json::json!({"type": "curve", "channel": "g1", "unit": "arcsec", "tau": [1.0]});
        let text = serde_json::to_string(&UnitRecord {
            unit: "imu07",
            record: &one,
        })
        .unwrap();
        // serde_json's own maps sort their keys; the wrapper keeps the record's order.
        assert_eq!(
            text,
            r#"{"channel":"g1","tau":[1.0],"type":"curve","unit":"imu07","channel_unit":"arcsec"}"#
        );
        let mut back: Value = serde_json::from_str(&text).unwrap();
        assert_eq!(untag(&mut back).as_deref(), Some("imu07"));
        assert_eq!(back, one);
    }

    /// A health record (no channel unit): `unit` is the unit's name, after `type`.
    #[test]
    fn health_round_trip() {
        let h = HealthRecord {
            frames: 7,
            ..HealthRecord::default()
        };
        let text = serde_json::to_string(&UnitRecord {
            unit: "bay-3",
            record: &h,
        })
        .unwrap();
        assert!(
            text.starts_with(r#"{"type":"health","unit":"bay-3","frames":7,"#),
            "{text}"
        );
        let mut back: Value = serde_json::from_str(&text).unwrap();
        assert_eq!(untag(&mut back).as_deref(), Some("bay-3"));
        let plain: Value = serde_json::to_value(&h).unwrap();
        assert_eq!(back, plain);
        // A one-unit record is left alone.
        let mut one = plain.clone();
        assert_eq!(untag(&mut one), None);
        assert_eq!(one, plain);
    }
}
