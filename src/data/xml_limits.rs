//! A cheap pass over an XML file's text before `roxmltree` parses it: elements with more
//! attributes than any real export are refused, since the parser checks each attribute against
//! the element's others (quadratic in their number: 100,000 attributes take minutes).

use super::DataError;
use std::path::Path;

/// The most attributes one element may have. Kinovea and Tracker write a handful; 1,000 keeps
/// the parser's check under a million comparisons per element.
pub const MAX_ATTRIBUTES: usize = 1000;

/// Refuse `text` (the file `path`) if an element has more than [`MAX_ATTRIBUTES`] attributes,
/// naming the line. One pass: comments, CDATA, processing instructions and declarations are
/// skipped whole, and attributes are counted by their `=` outside quoted values. What is not
/// well-formed is left to the parser to report.
pub fn check_attributes(text: &str, path: &Path) -> Result<(), DataError> {
    let b = text.as_bytes();
    let skip_to = |from: usize, end: &str| {
        text[from..]
            .find(end)
            .map_or(b.len(), |k| from + k + end.len())
    };
    let mut i = 0;
    while let Some(k) = text[i..].find('<') {
        let start = i + k;
        let rest = &text[start..];
        if rest.starts_with("<!--") {
            i = skip_to(start + 4, "-->");
        } else if rest.starts_with("<![CDATA[") {
            i = skip_to(start + 9, "]]>");
        } else if rest.starts_with("<?") {
            i = skip_to(start + 2, "?>");
        } else if rest.starts_with("<!") || rest.starts_with("</") {
            i = skip_to(start + 2, ">");
        } else {
            let (mut quote, mut count, mut j) = (None, 0usize, start + 1);
            while let Some(&c) = b.get(j) {
                match (quote, c) {
                    (Some(q), c) if c == q => quote = None,
                    (Some(_), _) => {}
                    (None, b'"' | b'\'') => quote = Some(c),
                    (None, b'=') => count += 1,
                    (None, b'>') => break,
                    _ => {}
                }
                j += 1;
            }
            if count > MAX_ATTRIBUTES {
                let line = 1 + b[..start].iter().filter(|&&c| c == b'\n').count();
                let name: String = rest[1..]
                    .chars()
                    .take_while(|c| !c.is_whitespace() && *c != '>' && *c != '/')
                    .take(40)
                    .collect();
                return Err(DataError::parse(
                    path,
                    format!("line {line}"),
                    format!("element <{name}>"),
                    format!("at most {MAX_ATTRIBUTES} attributes per element"),
                    format!("{count}; refusing to parse it"),
                ));
            }
            i = (j + 1).min(b.len());
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn attributes_are_counted_outside_quotes_comments_and_cdata() {
        let p = Path::new("a.xml");
        let ok = r#"<?xml version="1.0"?><!-- a=b c=d --><a x="1=2" y='=' z="3"><![CDATA[ <b q=1> ]]></a>"#;
        check_attributes(ok, p).unwrap();
        let many: String = (0..=MAX_ATTRIBUTES)
            .map(|k| format!(" a{k}=\"{k}\""))
            .collect();
        let bad = format!("<?xml version=\"1.0\"?>\n<r>\n<e{many}/></r>");
        let e = check_attributes(&bad, p).unwrap_err().to_string();
        assert!(e.contains("line 3") && e.contains("1000 attributes"), "{e}");
        check_attributes(&format!("<e{}/>", &many[..many.rfind(' ').unwrap()]), p).unwrap();
    }
}
