//! The declared formats ([`pdw_store::format`]) against `docs/hdf5.md`: each format's table in
//! the docs is the one generated from its declaration. `PDW_UPDATE_DOCS=1` rewrites the tables
//! in place (then review and commit the diff).

use pdw_store::format::{Format, Item, Unit, ALL};

fn docs_path() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/hdf5.md")
}

fn markers(f: &Format) -> (String, String) {
    (
        format!(
            "<!-- format {}: generated from pdw_store::format::{}, checked by \
             crates/pdw-store/tests/formats.rs -->\n",
            f.name,
            f.name.to_uppercase()
        ),
        format!("<!-- end format {} -->", f.name),
    )
}

/// `text` with each format's generated table replaced by the current one; the names of the
/// formats whose markers are missing.
fn regenerate(text: &str) -> (String, Vec<&'static str>) {
    let mut out = text.to_string();
    let mut missing = Vec::new();
    for f in ALL {
        let (open, close) = markers(f);
        match (out.find(&open), out.find(&close)) {
            (Some(a), Some(b)) if b > a => {
                out.replace_range(a + open.len()..b, &f.markdown());
            }
            _ => missing.push(f.name),
        }
    }
    (out, missing)
}

#[test]
fn docs_hdf5_md_tables_are_the_declared_formats() {
    let path = docs_path();
    let text = std::fs::read_to_string(&path).unwrap();
    let (fresh, missing) = regenerate(&text);
    assert!(
        missing.is_empty(),
        "docs/hdf5.md has no table for {missing:?}"
    );
    if std::env::var_os("PDW_UPDATE_DOCS").is_some() {
        std::fs::write(&path, &fresh).unwrap();
        return;
    }
    assert!(
        fresh == text,
        "docs/hdf5.md's format tables are stale: run this test with PDW_UPDATE_DOCS=1"
    );
}

#[test]
fn every_format_declares_each_path_once_and_every_dataset_a_unit() {
    for f in ALL {
        let items: Vec<&Item> = f.items().collect();
        for (k, i) in items.iter().enumerate() {
            assert!(
                !items[..k].iter().any(|j| j.path == i.path),
                "{}: {} declared twice",
                f.name,
                i.path
            );
            let dataset = !i.is_attr() && i.dtype != "group";
            assert_eq!(
                dataset,
                i.unit != Unit::None,
                "{}: {} (a dataset carries a unit, nothing else does)",
                f.name,
                i.path
            );
        }
    }
}

#[test]
fn placeholders_match_one_name_without_a_slash() {
    let i = Item::attr("metrics@fraction_<name>", "f64", "");
    assert!(i.matches("metrics@fraction_gait"));
    assert!(!i.matches("metrics@fraction_"));
    let s = Item::group("attractors/<name>/section", "");
    assert!(s.matches("attractors/period-2/section"));
    assert!(!s.matches("attractors/a/b/section"));
    assert!(!s.matches("attractors/section"));
}
