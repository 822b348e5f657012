//! Units of a spec's parameters: a small table, so that a value with a unit means what it says.
//!
//! A parameter in a spec's `[parameters]` carries a unit (`{ value = 3, unit = "deg" }`). The
//! walker computes in one unit per quantity — radians for angles and, in an SI spec, m, kg and
//! s — so a value is converted into that unit when the spec is read, and a unit the table does
//! not know is refused, never ignored:
//!
//! | atoms | converted to | where |
//! |---|---|---|
//! | `rad`, `deg`, `°` | rad (`deg`: × π ÷ 180) | every spec |
//! | `m`, `cm`, `mm` | m (÷ 100, ÷ 1000) | SI specs |
//! | `kg`, `g` | kg (÷ 1000) | SI specs |
//! | `s`, `ms` | s (÷ 1000) | SI specs |
//! | `N` | N | SI specs |
//! | `L`, `M`, `T` | taken as is | abstract unit systems (a preset's own length, mass, time: the kneed preset, after Hsu Chen 2007) |
//! | `1` | taken as is (dimensionless) | every spec |
//!
//! A unit is one atom or a product of atoms with integer powers: `m/s^2`, `kg m^2`, `L/T^2`,
//! `1/s` (`*`, `·` or a space multiply, `/` divides by the next atom only, `^` gives a power;
//! no parentheses). Its value is converted atom by atom (`cm/s^2`: ÷ 100; `g cm^2`: ÷ 1000,
//! ÷ 100 twice), each step correctly rounded, and a unit whose
//! atoms are all base atoms (`rad`, `m`, `kg`, `s`, `m/s^2`, `L`, `1`) leaves the value untouched
//! bit for bit. A spec is **abstract** when one of its parameters uses `L`, `M` or `T`: its lengths,
//! masses and times are in the preset's own units, which a metric prefix cannot be converted
//! into, so `cm`, `mm`, `g` and `ms` are refused there (`m`, `kg`, `s` are taken as written,
//! as before). A unit mixing SI and abstract atoms is refused.

/// Which unit system a spec's lengths, masses and times are in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum UnitSystem {
    /// m, kg, s (and their prefixes in the table).
    Si,
    /// A model's own units `L`, `M`, `T` (e.g. Hsu Chen's, leg length L = 1).
    Abstract,
}

/// How an atom's value becomes a value in its base atom: `v · num / den`, each step correctly
/// rounded (`cm`: `v / 100`, where `v · 0.01` rounds twice; `deg`: `v · π / 180`).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Scale {
    num: f64,
    den: f64,
}

/// The base atom itself: `v · 1 / 1`, the value bit for bit.
const ONE: Scale = Scale { num: 1.0, den: 1.0 };

const fn ratio(num: f64, den: f64) -> Scale {
    Scale { num, den }
}

/// Degrees to radians: `v · π / 180`, so that 3° is 0.05235987755982988 (the compass preset's
/// slope, the double nearest 3π/180); `f64::to_radians` multiplies by the rounded π/180 and
/// gives 0.05235987755982989.
const DEG: Scale = ratio(std::f64::consts::PI, 180.0);

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Family {
    /// Angles and `1`: meaningful in every system.
    Any,
    Si,
    Abstract,
}

/// One atom of the table: its name, its base atom, the scale to it, the system it belongs to.
struct Atom {
    name: &'static str,
    base: &'static str,
    scale: Scale,
    family: Family,
}

const fn atom(name: &'static str, base: &'static str, scale: Scale, family: Family) -> Atom {
    Atom {
        name,
        base,
        scale,
        family,
    }
}

/// The table (module docs).
const ATOMS: [Atom; 15] = [
    atom("rad", "rad", ONE, Family::Any),
    atom("deg", "rad", DEG, Family::Any),
    atom("°", "rad", DEG, Family::Any),
    atom("1", "1", ONE, Family::Any),
    atom("m", "m", ONE, Family::Si),
    atom("cm", "m", ratio(1.0, 100.0), Family::Si),
    atom("mm", "m", ratio(1.0, 1000.0), Family::Si),
    atom("kg", "kg", ONE, Family::Si),
    atom("g", "kg", ratio(1.0, 1000.0), Family::Si),
    atom("s", "s", ONE, Family::Si),
    atom("ms", "s", ratio(1.0, 1000.0), Family::Si),
    atom("N", "N", ONE, Family::Si),
    atom("L", "L", ONE, Family::Abstract),
    atom("M", "M", ONE, Family::Abstract),
    atom("T", "T", ONE, Family::Abstract),
];

/// The accepted units, for messages.
pub const ACCEPTED: &str = "rad, deg, ° (angles, converted to rad); m, cm, mm; kg, g; s, ms; N \
     (SI specs, converted to m, kg, s); L, M, T (a model's own length, mass and time, taken as \
     is); 1 (dimensionless); and products of these with integer powers such as m/s^2, kg m^2, \
     L/T^2";

/// One atom of a parsed unit: the table entry, its power, and where its name sits in the text.
struct Factor {
    atom: &'static Atom,
    power: i32,
    span: std::ops::Range<usize>,
}

/// Parses a unit into its atoms and powers (module docs: `a*b`, `a b`, `a·b`, `a/b`, `a^n`).
fn parse(unit: &str) -> Result<Vec<Factor>, String> {
    let text = unit.trim();
    if text.is_empty() {
        return Err("an empty unit (write \"1\" for a dimensionless parameter)".into());
    }
    let offset = unit.len() - unit.trim_start().len();
    let mut out = Vec::new();
    let mut divide = false;
    let mut i = 0;
    let bytes: Vec<(usize, char)> = text.char_indices().collect();
    while i < bytes.len() {
        let (at, c) = bytes[i];
        if c.is_whitespace() || c == '*' || c == '·' {
            i += 1;
            continue;
        }
        if c == '/' {
            if divide {
                return Err("two `/` in a row".into());
            }
            divide = true;
            i += 1;
            continue;
        }
        let st = i;
        if c == '1' || c == '°' {
            i += 1;
        } else {
            while i < bytes.len() && bytes[i].1.is_alphabetic() {
                i += 1;
            }
        }
        if i == st {
            return Err(format!("unexpected `{c}`"));
        }
        let end = bytes.get(i).map_or(text.len(), |b| b.0);
        let name = &text[at..end];
        let atom = ATOMS
            .iter()
            .find(|a| a.name == name)
            .ok_or_else(|| format!("`{name}` is not a unit pdw-sweep knows"))?;
        let mut power = 1;
        if bytes.get(i).is_some_and(|b| b.1 == '^') {
            i += 1;
            let ps = i;
            while i < bytes.len() && (bytes[i].1.is_ascii_digit() || (i == ps && bytes[i].1 == '-'))
            {
                i += 1;
            }
            let pe = bytes.get(i).map_or(text.len(), |b| b.0);
            let pstart = bytes.get(ps).map_or(text.len(), |b| b.0);
            power = text[pstart..pe]
                .parse::<i32>()
                .ok()
                .filter(|p| (-9..=9).contains(p))
                .ok_or_else(|| format!("`^{}` is not a power from -9 to 9", &text[pstart..pe]))?;
        }
        if divide {
            power = -power;
            divide = false;
        }
        out.push(Factor {
            atom,
            power,
            span: offset + at..offset + end,
        });
    }
    if divide {
        return Err("a `/` with nothing after it".into());
    }
    Ok(out)
}

/// The system of a unit's atoms (`None`: angles and `1` only), or an error when they mix.
fn family_of(factors: &[Factor]) -> Result<Option<UnitSystem>, String> {
    let si = factors.iter().any(|f| f.atom.family == Family::Si);
    let abs = factors.iter().any(|f| f.atom.family == Family::Abstract);
    match (si, abs) {
        (true, true) => Err("it mixes SI units with the abstract L, M, T".into()),
        (true, false) => Ok(Some(UnitSystem::Si)),
        (false, true) => Ok(Some(UnitSystem::Abstract)),
        (false, false) => Ok(None),
    }
}

/// Whether `unit` uses the abstract atoms `L`, `M`, `T` (an unparsable unit does not).
pub fn is_abstract(unit: &str) -> bool {
    parse(unit).ok().and_then(|f| family_of(&f).ok().flatten()) == Some(UnitSystem::Abstract)
}

/// The unit system of a spec whose parameters have `units`: abstract when any uses `L`, `M`
/// or `T`, else SI.
pub fn system_of<'a>(units: impl IntoIterator<Item = &'a str>) -> UnitSystem {
    if units.into_iter().any(is_abstract) {
        UnitSystem::Abstract
    } else {
        UnitSystem::Si
    }
}

/// `value` in `unit` converted into the base unit of a spec in `system`: the converted value
/// and the base unit's text (the unit as written when it is already a base unit). An error
/// says why the unit is refused (the caller adds the parameter and [`ACCEPTED`]).
pub fn to_base(value: f64, unit: &str, system: UnitSystem) -> Result<(f64, String), String> {
    let factors = parse(unit)?;
    let fam = family_of(&factors)?;
    if system == UnitSystem::Abstract && fam == Some(UnitSystem::Si) {
        if let Some(f) = factors.iter().find(|f| f.atom.scale != ONE) {
            return Err(format!(
                "the spec's lengths, masses and times are in its own units (L, M, T), which `{}` \
                 cannot be converted into",
                f.atom.name
            ));
        }
    }
    let mut v = value;
    let mut base = String::with_capacity(unit.len());
    let mut last = 0;
    for f in &factors {
        for _ in 0..f.power.unsigned_abs() {
            let Scale { num, den } = f.atom.scale;
            v = if f.power > 0 {
                v * num / den
            } else {
                v * den / num
            };
        }
        base.push_str(&unit[last..f.span.start]);
        base.push_str(f.atom.base);
        last = f.span.end;
    }
    base.push_str(&unit[last..]);
    Ok((v, base))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base_units_leave_the_value_bit_for_bit() {
        for u in [
            "rad", "1", "m", "kg", "s", "m/s^2", "kg m^2", "L", "M", "T", "L/T^2", "N",
        ] {
            let x = 0.05235987755982988;
            for sys in [UnitSystem::Si, UnitSystem::Abstract] {
                assert_eq!(to_base(x, u, sys), Ok((x, u.to_string())), "{u}");
            }
        }
    }

    #[test]
    fn prefixes_and_degrees_convert() {
        let si = UnitSystem::Si;
        assert_eq!(
            to_base(3.0, "deg", si),
            Ok((0.05235987755982988, "rad".into()))
        );
        assert_eq!(
            to_base(3.0, "°", si),
            Ok((0.05235987755982988, "rad".into()))
        );
        assert_eq!(
            to_base(180.0, "deg", si),
            Ok((std::f64::consts::PI, "rad".into()))
        );
        assert_eq!(
            to_base(1.0, "1/deg", si).map(|p| p.0),
            Ok(180.0 / std::f64::consts::PI)
        );
        assert_eq!(to_base(50.0, "cm", si), Ok((0.5, "m".into())));
        assert_eq!(to_base(7.0, "mm", si), Ok((0.007, "m".into())));
        assert_eq!(to_base(250.0, "g", si), Ok((0.25, "kg".into())));
        assert_eq!(to_base(981.0, "cm/s^2", si), Ok((9.81, "m/s^2".into())));
        assert_eq!(to_base(2.0, "1/ms", si), Ok((2000.0, "1/s".into())));
        assert_eq!(to_base(5e6, "g cm^2", si), Ok((0.5, "kg m^2".into())));
    }

    #[test]
    fn unknown_mixed_or_unconvertible_units_are_refused() {
        let e = to_base(1.0, "furlong", UnitSystem::Si).unwrap_err();
        assert!(e.contains("`furlong`"), "{e}");
        assert!(to_base(1.0, "m/L", UnitSystem::Si)
            .unwrap_err()
            .contains("mixes"));
        let e = to_base(1.0, "cm", UnitSystem::Abstract).unwrap_err();
        assert!(e.contains("`cm`"), "{e}");
        assert!(to_base(1.0, "", UnitSystem::Si).is_err());
        assert!(to_base(1.0, "m/", UnitSystem::Si).is_err());
        assert!(to_base(1.0, "m^x", UnitSystem::Si).is_err());
        assert!(to_base(1.0, "(m)", UnitSystem::Si).is_err());
    }

    #[test]
    fn a_spec_is_abstract_when_a_parameter_uses_l_m_or_t() {
        assert_eq!(system_of(["rad", "L", "M"]), UnitSystem::Abstract);
        assert_eq!(system_of(["rad", "m", "kg", "1"]), UnitSystem::Si);
        assert_eq!(system_of(["L/T^2"]), UnitSystem::Abstract);
    }
}
