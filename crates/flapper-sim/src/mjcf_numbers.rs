//! A check of the MJCF text before MuJoCo compiles it: no numeric attribute may hold a NaN or an infinity
//! (`mass="nan"`, `kp="inf"`, `pos="0 1e999 0"`). MuJoCo parses such values without a word and the
//! simulation then flies on them, or stops on a warning after a step; refusing them at load names the
//! line and the attribute instead. Attributes that hold names or files are not numbers and are skipped.

/// Attributes whose values are names, files or keywords, never numbers.
const TEXT_ATTRIBUTES: [&str; 20] = [
    "name",
    "class",
    "childclass",
    "joint",
    "joint1",
    "joint2",
    "body",
    "body1",
    "body2",
    "site",
    "mesh",
    "material",
    "texture",
    "file",
    "target",
    "tendon",
    "actuator",
    "geom",
    "geom1",
    "geom2",
];

/// A non-finite number in the text: its line (1-based), the attribute and the attribute's whole value.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NonFiniteAttribute {
    pub line: usize,
    pub attribute: String,
    pub value: String,
}

/// The first attribute inside a tag (comments skipped) with a token that parses as a non-finite number.
pub fn first_non_finite(mjcf: &str) -> Option<NonFiniteAttribute> {
    let bytes = mjcf.as_bytes();
    let (mut i, mut in_tag) = (0, false);
    while i < bytes.len() {
        if mjcf[i..].starts_with("<!--") {
            i = mjcf[i..].find("-->").map_or(bytes.len(), |end| i + end + 3);
            continue;
        }
        match bytes[i] {
            b'<' => in_tag = true,
            b'>' => in_tag = false,
            b'"' | b'\'' if in_tag => {
                let quote = bytes[i] as char;
                let end = mjcf[i + 1..].find(quote).map_or(bytes.len(), |e| i + 1 + e);
                let value = &mjcf[i + 1..end.min(bytes.len())];
                let attribute = attribute_before(&mjcf[..i]);
                let numeric = !TEXT_ATTRIBUTES.contains(&attribute.as_str());
                if numeric && value.split_whitespace().any(|t| t.parse::<f64>().is_ok_and(|x| !x.is_finite())) {
                    let line = mjcf[..i].matches('\n').count() + 1;
                    return Some(NonFiniteAttribute { line, attribute, value: value.to_owned() });
                }
                i = end + 1;
                continue;
            }
            _ => {}
        }
        i += 1;
    }
    None
}

/// The attribute name before `...name =` at the end of `text`.
fn attribute_before(text: &str) -> String {
    let text = text.trim_end().strip_suffix('=').unwrap_or(text).trim_end();
    let start = text.rfind(|c: char| !(c.is_alphanumeric() || c == '_' || c == '-' || c == ':')).map_or(0, |k| k + 1);
    text[start..].to_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_non_finite_numbers_in_any_numeric_attribute_and_names_the_line() {
        let model =
            "<mujoco>\n  <worldbody>\n    <body name='nan' pos='0 0 1'>\n      <geom size='0.1' mass = \"NaN\"/>";
        assert_eq!(
            first_non_finite(model),
            Some(NonFiniteAttribute { line: 4, attribute: "mass".into(), value: "NaN".into() })
        );
        for (text, attribute) in [
            ("<position kp=\"inf\"/>", "kp"),
            ("<geom pos=\"0 1e999 0\"/>", "pos"),
            ("<geom fluidcoef='0.2 0.12 -infinity 3.14 1'/>", "fluidcoef"),
            ("<option timestep=\"+nan\"/>", "timestep"),
        ] {
            assert_eq!(first_non_finite(text).map(|f| f.attribute), Some(attribute.into()), "{text}");
        }
    }

    #[test]
    fn names_comments_and_text_outside_tags_are_not_numbers() {
        let model = "<mujoco><!-- mass=\"nan\" --><body name=\"inf\" childclass='NaN'><geom mesh=\"nan\" \
                     size=\"0.1\"/>nan inf</body></mujoco>";
        assert_eq!(first_non_finite(model), None);
        assert_eq!(first_non_finite(crate::ROBOT_MJCF), None, "the shipped robot is finite");
    }
}
