//! Whether a robot description holds xacro, found by reading it as XML:
//! an element or attribute in the xacro namespace (the `xacro:` prefix, or
//! a prefix bound to xacro's URI), or a `${...}`/`$(...)` substitution in
//! an attribute value or a text node. Comments, CDATA sections, processing
//! instructions and the document type are not markup: a commented-out
//! `<xacro:include filename="$(find ...)"/>` is text nobody expands (and
//! xacro keeps it in its output).

use quick_xml::events::{BytesStart, Event};
use quick_xml::Reader;

/// How much of xacro a robot description holds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Markup {
    /// Only the namespace declaration: plain URDF that xacro would leave as
    /// it is (published descriptions often declare it and use none).
    Namespace,
    /// Elements or substitutions that only xacro can expand (the reason).
    Needed(&'static str),
}

/// The first piece of xacro markup in a text, and where.
#[derive(Debug, Clone, PartialEq)]
pub struct Found {
    /// 1-based line.
    pub line: usize,
    /// What it is: `<xacro:if>`, or the substitution as written.
    pub what: String,
    /// The element it is in (its tag) and, for an attribute, the attribute.
    pub place: String,
    /// Whether it is a substitution (`${...}`, `$(...)`) rather than an
    /// element or attribute of the xacro namespace.
    pub substitution: bool,
}

/// Whether a prefix names the xacro namespace: `xacro`, or one declared
/// with xacro's URI (`http://ros.org/wiki/xacro`, `http://www.ros.org/wiki/xacro`).
fn xacro_prefix(prefix: &[u8], bound: &[Vec<u8>]) -> bool {
    prefix == b"xacro" || bound.iter().any(|p| p.as_slice() == prefix)
}

fn is_xacro_uri(uri: &[u8]) -> bool {
    let u = String::from_utf8_lossy(uri);
    let u = u.trim_end_matches('/');
    u.ends_with("ros.org/wiki/xacro")
}

/// `${` or `$(` in `bytes`, at its byte offset.
fn substitution(bytes: &[u8]) -> Option<usize> {
    bytes
        .windows(2)
        .position(|w| w[0] == b'$' && (w[1] == b'{' || w[1] == b'('))
}

/// The substitution starting at `at` in `s`, up to its closing bracket
/// (or 60 characters).
fn excerpt(s: &str, at: usize) -> String {
    let rest = &s[at..];
    let close = if rest.as_bytes().get(1) == Some(&b'{') {
        '}'
    } else {
        ')'
    };
    let end = rest
        .char_indices()
        .find(|&(_, c)| c == close)
        .map_or(rest.len(), |(i, _)| i + 1);
    let mut out: String = rest[..end].chars().take(60).collect();
    if out.len() < end {
        out.push('…');
    }
    out
}

/// What one reading of a text found.
#[derive(Debug, Default)]
struct Scan {
    /// The namespace is declared.
    namespace: bool,
    /// The first xacro element or attribute.
    element: Option<Found>,
    /// The first substitution.
    substitution: Option<Found>,
}

fn line_at(text: &str, byte: usize) -> usize {
    text.as_bytes()[..byte.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// Read `text` to its end, or to the first problem of its XML (what was
/// read before it counts).
fn scan(text: &str) -> Scan {
    let mut out = Scan::default();
    let mut reader = Reader::from_str(text);
    reader.config_mut().check_end_names = false;
    // Prefixes declared with xacro's URI (scopes ignored: a prefix bound to
    // it anywhere is xacro's).
    let mut bound: Vec<Vec<u8>> = Vec::new();
    let mut stack: Vec<String> = Vec::new();
    loop {
        let before = reader.buffer_position() as usize;
        let event = match reader.read_event() {
            Ok(e) => e,
            Err(_) => {
                return out;
            }
        };
        match event {
            Event::Start(e) => {
                let tag = String::from_utf8_lossy(e.name().as_ref()).into_owned();
                if element(&mut out, &mut bound, &e, &tag, text, before).is_err() {
                    return out;
                }
                stack.push(tag);
            }
            Event::Empty(e) => {
                let tag = String::from_utf8_lossy(e.name().as_ref()).into_owned();
                if element(&mut out, &mut bound, &e, &tag, text, before).is_err() {
                    return out;
                }
            }
            Event::End(_) => {
                stack.pop();
            }
            Event::Text(t) => {
                let raw: &[u8] = &t;
                if out.substitution.is_none() {
                    if let Some(i) = substitution(raw) {
                        let s = String::from_utf8_lossy(raw);
                        let tag = stack.last().cloned().unwrap_or_default();
                        out.substitution = Some(Found {
                            line: line_at(text, before + i),
                            what: excerpt(&s, i),
                            place: format!("the text of <{tag}>"),
                            substitution: true,
                        });
                    }
                }
            }
            Event::Eof => return out,
            // Comments, CDATA, processing instructions, the declaration,
            // the document type and entity references expand nothing.
            _ => {}
        }
    }
}

/// Note what the start tag `e` holds; `Err` when its attributes are not XML.
fn element(
    out: &mut Scan,
    bound: &mut Vec<Vec<u8>>,
    e: &BytesStart<'_>,
    tag: &str,
    text: &str,
    at: usize,
) -> Result<(), ()> {
    let line = line_at(text, at);
    let mut attrs = Vec::new();
    for a in e.attributes().with_checks(false) {
        let a = a.map_err(|_| ())?;
        let key = a.key.as_ref().to_vec();
        if let Some(p) = key.strip_prefix(b"xmlns:") {
            if p == b"xacro" || is_xacro_uri(&a.value) {
                out.namespace = true;
                if is_xacro_uri(&a.value) {
                    bound.push(p.to_vec());
                }
            }
            continue;
        }
        attrs.push((key, a.value.into_owned()));
    }
    if out.element.is_none() {
        if let Some(p) = e.name().prefix() {
            if xacro_prefix(p.as_ref(), bound) {
                out.element = Some(Found {
                    line,
                    what: format!("<{tag}>"),
                    place: format!("<{tag}>"),
                    substitution: false,
                });
            }
        }
    }
    for (key, value) in &attrs {
        let name = String::from_utf8_lossy(key);
        if out.element.is_none() {
            let prefix = key.iter().position(|&b| b == b':').map(|i| &key[..i]);
            if prefix.is_some_and(|p| xacro_prefix(p, bound)) {
                out.element = Some(Found {
                    line,
                    what: format!("the attribute `{name}`"),
                    place: format!("<{tag}>"),
                    substitution: false,
                });
            }
        }
        if out.substitution.is_none() {
            if let Some(i) = substitution(value) {
                let v = String::from_utf8_lossy(value);
                out.substitution = Some(Found {
                    line,
                    what: excerpt(&v, i),
                    place: format!(
                        "<{tag} {name}=\"{}\">",
                        v.chars().take(80).collect::<String>()
                    ),
                    substitution: true,
                });
            }
        }
    }
    Ok(())
}

/// The xacro in `text`, if any: xacro elements or attributes, `${...}` or
/// `$(...)` substitutions, or the namespace alone. A text that is not
/// well-formed XML holds xacro when its readable part does (xacro then
/// says what is wrong with it).
pub fn markup(text: &str) -> Option<Markup> {
    let s = scan(text);
    if s.element.is_some() {
        Some(Markup::Needed("xacro elements"))
    } else if s.substitution.is_some() {
        Some(Markup::Needed("${...} or $(...) substitutions"))
    } else if s.namespace {
        Some(Markup::Namespace)
    } else {
        None
    }
}

/// The first xacro element, attribute or substitution of `text` (an
/// expansion, which should hold none), with its line.
pub fn leftover(text: &str) -> Option<Found> {
    let s = scan(text);
    match (s.element, s.substitution) {
        (Some(a), Some(b)) => Some(if b.line < a.line { b } else { a }),
        (a, b) => a.or(b),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const NS: &str = "xmlns:xacro=\"http://ros.org/wiki/xacro\"";

    #[test]
    fn markup_is_read_from_the_xml() {
        let doc = |body: &str| {
            format!("<?xml version=\"1.0\"?>\n<robot name=\"r\" {NS}>\n{body}\n</robot>\n")
        };
        assert_eq!(markup(&doc("<link name=\"a\"/>")), Some(Markup::Namespace));
        assert!(markup("<robot name=\"r\"><link name=\"a\"/></robot>").is_none());
        // Comments, CDATA and processing instructions are not markup.
        for quiet in [
            "<!-- <xacro:include filename=\"$(find p)/urdf/c.urdf\"/> -->",
            "<gazebo><![CDATA[ ${not} $(this) ]]></gazebo>",
            "<?xacro $(find p) ?>",
        ] {
            assert_eq!(markup(&doc(quiet)), Some(Markup::Namespace), "{quiet}");
        }
        assert_eq!(
            markup(&doc("<xacro:property name=\"a\" value=\"1\"/>")),
            Some(Markup::Needed("xacro elements"))
        );
        // Another prefix bound to xacro's URI, and an attribute of it.
        let other =
            "<robot xmlns:x=\"http://www.ros.org/wiki/xacro\"><x:macro name=\"m\"/></robot>";
        assert_eq!(markup(other), Some(Markup::Needed("xacro elements")));
        let attr = format!("<robot {NS}><link name=\"a\" xacro:foo=\"1\"/></robot>");
        let f = leftover(&attr).unwrap();
        assert_eq!(f.what, "the attribute `xacro:foo`");
        for sub in ["<link name=\"${p}a\"/>", "<plugin>$(arg x)</plugin>"] {
            assert_eq!(
                markup(&doc(sub)),
                Some(Markup::Needed("${...} or $(...) substitutions")),
                "{sub}"
            );
        }
        // The undeclared `xacro:` prefix is xacro's too.
        assert!(matches!(
            markup("<robot><xacro:include filename=\"a\"/></robot>"),
            Some(Markup::Needed(_))
        ));
    }

    #[test]
    fn leftovers_say_where() {
        let text =
            "<robot name=\"r\">\n  <!-- ${fine} -->\n  <link name=\"${prefix}base\"/>\n</robot>\n";
        let f = leftover(text).unwrap();
        assert_eq!(f.line, 3);
        assert_eq!(f.what, "${prefix}");
        assert!(
            f.place.starts_with("<link name=\"${prefix}base\""),
            "{}",
            f.place
        );
        let text = "<robot>\n<a>\n\n  x $(arg y) z</a></robot>";
        let f = leftover(text).unwrap();
        assert_eq!((f.line, f.what.as_str()), (4, "$(arg y)"));
        assert!(leftover("<robot><!-- $(find x) --><link name='a'/></robot>").is_none());
    }

    #[test]
    fn malformed_xml_keeps_what_was_read() {
        // A xacro file with an XML error further down: xacro says what it is.
        let text =
            format!("<robot {NS}>\n<xacro:property name=\"a\" value=\"1\"/>\n<link>\n</robot>");
        assert!(matches!(markup(&text), Some(Markup::Needed(_))));
        assert!(markup("<robot><link name=\"a\"></robot").is_none());
    }
}
