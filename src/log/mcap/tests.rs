//! Tests of the MCAP writer.

use crate::log::mcap::*;
use serde::ser::{SerializeMap, SerializeStruct};
use serde::{Serialize, Serializer};

/// The message as serde_json writes a struct {t, segment, values} with
/// `values` a map in key order (what `JsonMsg::write` replaced).
struct Reference<'a>(f64, &'a str, &'a [Cow<'a, str>], &'a [f64]);

impl Serialize for Reference<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        struct Values<'a>(&'a [Cow<'a, str>], &'a [f64]);
        impl Serialize for Values<'_> {
            fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                let mut m = s.serialize_map(Some(self.0.len()))?;
                for (n, v) in self.0.iter().zip(self.1) {
                    m.serialize_entry(n.as_ref(), v)?;
                }
                m.end()
            }
        }
        let mut st = s.serialize_struct("Msg", 3)?;
        st.serialize_field("t", &self.0)?;
        st.serialize_field("segment", self.1)?;
        st.serialize_field("values", &Values(self.2, self.3))?;
        st.end()
    }
}

#[test]
fn json_messages_are_serde_jsons_bytes() {
    let names: Vec<Cow<'_, str>> = ["x", "a \"quoted\" name", "ψ\n\\", ""]
        .into_iter()
        .map(Cow::Borrowed)
        .collect();
    let rows: [&[f64]; 4] = [
        &[0.0, -0.0, 1.0, 1e300],
        &[f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 5e-324],
        &[0.1 + 0.2, -123456.789, 1e-7, 2f64.powi(60)],
        &[],
    ];
    for (i, values) in rows.into_iter().enumerate() {
        let n = values.len();
        let (t, seg) = (0.001 * i as f64, ["OP", "P2 \"b\"", "", "é\t"][i]);
        let keys = Keys::new(&names[..n]);
        let mut mine = Vec::new();
        JsonMsg {
            t,
            segment: seg,
            keys: &keys,
            values,
        }
        .write(&mut mine)
        .unwrap();
        let reference = serde_json::to_vec(&Reference(t, seg, &names[..n], values)).unwrap();
        assert_eq!(
            String::from_utf8(mine).unwrap(),
            String::from_utf8(reference).unwrap()
        );
    }
}

#[test]
fn offset_rotates_into_parent_frame() {
    let h = std::f64::consts::FRAC_1_SQRT_2;
    // 90° about x maps local +z to parent −y.
    let p = Pose {
        translation: [1.0, 2.0, 3.0],
        rotation: [h, 0.0, 0.0, h],
    };
    let o = offset(&p, [0.0, 0.0, 1.0]);
    for (a, b) in o.translation.iter().zip([1.0, 1.0, 3.0]) {
        assert!((a - b).abs() < 1e-12, "{:?}", o.translation);
    }
    assert_eq!(o.rotation, p.rotation);
}
