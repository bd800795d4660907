//! `fmuResourceLocation` is a URI (RFC 3986, `file` scheme, RFC 8089), not a path with a fixed
//! prefix: `file:///home/a%20b/resources`, `file:/home/a%20b/resources` and
//! `file://localhost/...` all name the same directory, and percent-escapes are decoded.

use crate::{Error, Result};
use std::path::PathBuf;

/// Turns a `file:` URI into a local path. A plain absolute path is accepted too (some masters
/// pass one). Other schemes, remote hosts and malformed escapes are errors.
pub fn file_uri_to_path(uri: &str) -> Result<PathBuf> {
    let bad =
        |why: &str| Error::invalid("fmuResourceLocation", uri, format!("a file: URI ({why})"));
    let rest = match uri.get(..5) {
        Some(scheme) if scheme.eq_ignore_ascii_case("file:") => &uri[5..],
        _ if uri.starts_with('/') => return Ok(PathBuf::from(uri)),
        _ => return Err(bad("unsupported scheme")),
    };
    let path = if let Some(after) = rest.strip_prefix("//") {
        // file://host/path: the authority must be empty or localhost.
        let slash = after.find('/').unwrap_or(after.len());
        let host = &after[..slash];
        if !host.is_empty() && !host.eq_ignore_ascii_case("localhost") {
            return Err(bad("remote host"));
        }
        &after[slash..]
    } else {
        rest
    };
    if !path.starts_with('/') {
        return Err(bad("path is not absolute"));
    }
    // Query and fragment are not part of the path.
    let path = path.split(['?', '#']).next().unwrap_or(path);
    let decoded = percent_decode(path).ok_or_else(|| bad("malformed percent-escape"))?;
    let decoded = String::from_utf8(decoded).map_err(|_| bad("not UTF-8 after decoding"))?;
    Ok(PathBuf::from(windows_drive(decoded)))
}

/// On Windows `/C:/dir` names `C:/dir`.
fn windows_drive(path: String) -> String {
    let b = path.as_bytes();
    if cfg!(windows) && b.len() >= 3 && b[0] == b'/' && b[1].is_ascii_alphabetic() && b[2] == b':' {
        path[1..].to_string()
    } else {
        path
    }
}

fn percent_decode(s: &str) -> Option<Vec<u8>> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let hex = b.get(i + 1..i + 3)?;
            let hex = std::str::from_utf8(hex).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn accepts_the_usual_forms() {
        for uri in [
            "file:///tmp/a%20b/res",
            "file:/tmp/a%20b/res",
            "file://localhost/tmp/a%20b/res",
            "FILE:///tmp/a b/res",
        ] {
            assert_eq!(
                file_uri_to_path(uri).unwrap(),
                PathBuf::from("/tmp/a b/res"),
                "{uri}"
            );
        }
        assert_eq!(
            file_uri_to_path("/plain/path").unwrap(),
            PathBuf::from("/plain/path")
        );
        assert_eq!(
            file_uri_to_path("file:///x/%C3%A9t%C3%A9").unwrap(),
            PathBuf::from("/x/été")
        );
    }

    #[test]
    fn rejects_malformed() {
        for uri in [
            "http://x/y",
            "file://server/share",
            "file:relative/x",
            "file:///a%2",
            "file:///a%zz",
            "",
            "res",
        ] {
            let e = file_uri_to_path(uri).unwrap_err().to_string();
            assert!(e.contains("fmuResourceLocation"), "{uri}: {e}");
        }
    }
}
