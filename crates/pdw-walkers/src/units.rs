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
//!
//! Every unit also says what it measures ([`Dimension`]: powers of length, mass, time and
//! angle; `N m` is a torque, `N m s` an angular impulse), and so does every parameter's role in
//! a model (a segment's `mass` is a mass, the slope an angle, `max_stride_time` a time): a unit
//! of another quantity is refused naming both — "unit `deg` is an angle, hip_mass is a mass
//! (kg, g, …)" — instead of being converted into a number of the wrong kind. A spec's
//! expressions are checked in their parameters' units (`a + b` with `a` in `rad` and `b` in `m`
//! adds an angle to a length); a value typed on a command line goes through [`convert`] with
//! its parameter's dimension.

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

/// One atom of the table: its name, its base atom, the scale to it, the system it belongs to
/// and the quantity it measures.
struct Atom {
    name: &'static str,
    base: &'static str,
    scale: Scale,
    family: Family,
    dim: Dimension,
}

const fn atom(
    name: &'static str,
    base: &'static str,
    scale: Scale,
    family: Family,
    dim: Dimension,
) -> Atom {
    Atom {
        name,
        base,
        scale,
        family,
        dim,
    }
}

/// The table (module docs).
const ATOMS: [Atom; 15] = [
    atom("rad", "rad", ONE, Family::Any, Dimension::ANGLE),
    atom("deg", "rad", DEG, Family::Any, Dimension::ANGLE),
    atom("°", "rad", DEG, Family::Any, Dimension::ANGLE),
    atom("1", "1", ONE, Family::Any, Dimension::DIMENSIONLESS),
    atom("m", "m", ONE, Family::Si, Dimension::LENGTH),
    atom("cm", "m", ratio(1.0, 100.0), Family::Si, Dimension::LENGTH),
    atom("mm", "m", ratio(1.0, 1000.0), Family::Si, Dimension::LENGTH),
    atom("kg", "kg", ONE, Family::Si, Dimension::MASS),
    atom("g", "kg", ratio(1.0, 1000.0), Family::Si, Dimension::MASS),
    atom("s", "s", ONE, Family::Si, Dimension::TIME),
    atom("ms", "s", ratio(1.0, 1000.0), Family::Si, Dimension::TIME),
    atom("N", "N", ONE, Family::Si, Dimension::FORCE),
    atom("L", "L", ONE, Family::Abstract, Dimension::LENGTH),
    atom("M", "M", ONE, Family::Abstract, Dimension::MASS),
    atom("T", "T", ONE, Family::Abstract, Dimension::TIME),
];

/// The accepted units, for messages.
pub const ACCEPTED: &str = "rad, deg, ° (angles, converted to rad); m, cm, mm; kg, g; s, ms; N \
     (SI specs, converted to m, kg, s); L, M, T (a model's own length, mass and time, taken as \
     is); 1 (dimensionless); and products of these with integer powers such as m/s^2, kg m^2, \
     N m, N m s, L/T^2";

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

/// What a quantity measures: the powers of length, mass, time and angle it is made of (a torque
/// is mass · length² / time², an angular rate angle / time). Every unit of the table has one,
/// and so has every parameter's role in a model (a segment's mass is a mass, the slope an
/// angle), so that a unit of another quantity is refused rather than converted: 572.96 `deg` is
/// not 10 kg.
///
/// Angles are their own dimension, so that `rad` is not a length, with one allowance: a value
/// without an angle where an angle is expected is taken as radians (`slope = 0.05` with unit
/// `1`, a gait rate in `1/s`), as the walker computes in radians.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dimension {
    pub length: f64,
    pub mass: f64,
    pub time: f64,
    pub angle: f64,
}

const fn dim(length: f64, mass: f64, time: f64, angle: f64) -> Dimension {
    Dimension {
        length,
        mass,
        time,
        angle,
    }
}

impl Dimension {
    pub const DIMENSIONLESS: Self = dim(0.0, 0.0, 0.0, 0.0);
    pub const ANGLE: Self = dim(0.0, 0.0, 0.0, 1.0);
    pub const LENGTH: Self = dim(1.0, 0.0, 0.0, 0.0);
    pub const MASS: Self = dim(0.0, 1.0, 0.0, 0.0);
    pub const TIME: Self = dim(0.0, 0.0, 1.0, 0.0);
    /// Length / time².
    pub const ACCELERATION: Self = dim(1.0, 0.0, -2.0, 0.0);
    /// Mass · length / time² (`N`).
    pub const FORCE: Self = dim(1.0, 1.0, -2.0, 0.0);
    /// Mass · length² (a rotational inertia, `kg m^2`).
    pub const INERTIA: Self = dim(2.0, 1.0, 0.0, 0.0);
    /// Force · length (`N m`).
    pub const TORQUE: Self = dim(2.0, 1.0, -2.0, 0.0);
    /// Torque · time (`N m s`): the angular impulse of an impact.
    pub const IMPULSE: Self = dim(2.0, 1.0, -1.0, 0.0);
    /// Angle / time (`rad/s`): a gait's joint rates.
    pub const ANGULAR_RATE: Self = dim(0.0, 0.0, -1.0, 1.0);

    /// The product of two quantities' dimensions.
    pub fn times(self, o: Self) -> Self {
        dim(
            self.length + o.length,
            self.mass + o.mass,
            self.time + o.time,
            self.angle + o.angle,
        )
    }

    /// The dimension of the `p`-th power.
    pub fn pow(self, p: f64) -> Self {
        dim(
            self.length * p,
            self.mass * p,
            self.time * p,
            self.angle * p,
        )
    }

    /// Whether a value of dimension `given` may stand where `self` is expected: the same
    /// dimension, or the same but for an angle `given` lacks (a plain number is radians).
    pub fn accepts(self, given: Self) -> bool {
        given == self || (given.angle == 0.0 && given == Self { angle: 0.0, ..self })
    }

    /// The quantity's name with its article ("a mass", "an angle"), or "a quantity in" its SI
    /// base units for a dimension without a name.
    pub fn name(self) -> String {
        match NAMED.iter().find(|n| n.dim == self) {
            Some(n) => n.name.to_string(),
            None => format!("a quantity in {}", self.si_text()),
        }
    }

    /// Units of this dimension in `system`, for messages ("kg, g").
    pub fn examples(self, system: UnitSystem) -> String {
        match (NAMED.iter().find(|n| n.dim == self), system) {
            (Some(n), UnitSystem::Si) => n.si.to_string(),
            (Some(n), UnitSystem::Abstract) => n.abstract_units.to_string(),
            (None, _) => self.si_text(),
        }
    }

    /// The dimension in SI base units, e.g. `kg m^2/s`.
    fn si_text(self) -> String {
        let mut up = Vec::new();
        let mut down = Vec::new();
        for (p, u) in [
            (self.mass, "kg"),
            (self.length, "m"),
            (self.time, "s"),
            (self.angle, "rad"),
        ] {
            let side = if p > 0.0 { &mut up } else { &mut down };
            match p.abs() {
                0.0 => {}
                1.0 => side.push(u.to_string()),
                a => side.push(format!("{u}^{a}")),
            }
        }
        let num = if up.is_empty() {
            "1".to_string()
        } else {
            up.join(" ")
        };
        match down.len() {
            0 => num,
            1 => format!("{num}/{}", down[0]),
            _ => format!("{num}/({})", down.join(" ")),
        }
    }
}

/// A dimension with a name, and the units of it a message proposes.
struct Named {
    dim: Dimension,
    name: &'static str,
    si: &'static str,
    abstract_units: &'static str,
}

const fn named(
    dim: Dimension,
    name: &'static str,
    si: &'static str,
    abstract_units: &'static str,
) -> Named {
    Named {
        dim,
        name,
        si,
        abstract_units,
    }
}

/// The named dimensions (a new quantity of a model adds a row).
const NAMED: [Named; 11] = [
    named(Dimension::DIMENSIONLESS, "dimensionless", "1", "1"),
    named(Dimension::ANGLE, "an angle", "rad, deg, °", "rad, deg, °"),
    named(Dimension::LENGTH, "a length", "m, cm, mm", "L"),
    named(Dimension::MASS, "a mass", "kg, g", "M"),
    named(Dimension::TIME, "a time", "s, ms", "T"),
    named(
        Dimension::ACCELERATION,
        "an acceleration",
        "m/s^2, cm/s^2",
        "L/T^2",
    ),
    named(Dimension::FORCE, "a force", "N, kg m/s^2", "M L/T^2"),
    named(
        Dimension::INERTIA,
        "a moment of inertia",
        "kg m^2, g cm^2",
        "M L^2",
    ),
    named(Dimension::TORQUE, "a torque", "N m, N*m", "M L^2/T^2"),
    named(
        Dimension::IMPULSE,
        "an angular impulse",
        "N m s, N*m*s",
        "M L^2/T",
    ),
    named(
        Dimension::ANGULAR_RATE,
        "an angular rate",
        "rad/s, deg/s",
        "rad/T",
    ),
];

/// The dimension of `unit` (an error when the table cannot parse it).
pub fn dimension_of(unit: &str) -> Result<Dimension, String> {
    Ok(parse(unit)?.iter().fold(Dimension::DIMENSIONLESS, |d, f| {
        d.times(f.atom.dim.pow(f64::from(f.power)))
    }))
}

/// The refusal of a unit of dimension `given` for `what`, which is `expected`: "unit `deg` is an
/// angle, hip_mass is a mass (kg, g, …)".
pub fn mismatch(
    unit: &str,
    given: Dimension,
    what: &str,
    expected: Dimension,
    system: UnitSystem,
) -> String {
    let given = match given.name().as_str() {
        "dimensionless" => "is dimensionless".to_string(),
        n => format!("is {n}"),
    };
    let expected = match expected.name().as_str() {
        "dimensionless" => "is dimensionless (1)".to_string(),
        n => format!("is {n} ({}, …)", expected.examples(system)),
    };
    format!("unit `{}` {given}, {what} {expected}", unit.trim())
}

/// `value` in `unit` as a value of `what`, a quantity of dimension `expected`, in the base unit
/// of a spec in `system`: the one checked conversion every unit typed on a command line goes
/// through (`--set NAME=VALUE[unit]`, `--slope 3deg`, `--sd 1deg`). A unit the table does not
/// know, cannot convert in `system`, or of another dimension is refused ([`mismatch`]).
pub fn convert(
    value: f64,
    unit: &str,
    what: &str,
    expected: Dimension,
    system: UnitSystem,
) -> Result<f64, String> {
    let given = dimension_of(unit)?;
    if !expected.accepts(given) {
        return Err(mismatch(unit, given, what, expected, system));
    }
    to_base(value, unit, system).map(|(v, _)| v)
}

/// A typed quantity split into its number and its unit: `"3deg"`, `"3 deg"`, `"2.5e-3 m/s^2"`,
/// `"-3°"` give (`"3"`, `"deg"`) and so on; a plain number gives an empty unit. The number is
/// the longest prefix of the form `[+-]digits[.digits][e[+-]digits]`; nothing is parsed here.
pub fn split_quantity(text: &str) -> (&str, &str) {
    let t = text.trim();
    let b = t.as_bytes();
    let mut i = 0;
    let digits = |i: &mut usize| {
        while *i < b.len() && b[*i].is_ascii_digit() {
            *i += 1;
        }
    };
    if i < b.len() && (b[i] == b'+' || b[i] == b'-') {
        i += 1;
    }
    digits(&mut i);
    if i < b.len() && b[i] == b'.' {
        i += 1;
        digits(&mut i);
    }
    if i < b.len() && (b[i] == b'e' || b[i] == b'E') {
        let mut j = i + 1;
        if j < b.len() && (b[j] == b'+' || b[j] == b'-') {
            j += 1;
        }
        if j < b.len() && b[j].is_ascii_digit() {
            i = j;
            digits(&mut i);
        }
    }
    // a word that is a number (`inf`, `nan`) is left to the number's parser
    if !t[..i].bytes().any(|c| c.is_ascii_digit()) {
        return (t, "");
    }
    (t[..i].trim(), t[i..].trim())
}

/// A value in an expression over a spec's parameters when the spec's dimensions are checked: the
/// value and its dimension, `None` for a number written in the expression (it takes the
/// dimension of what it is added to, and none in a product: `0.5 * l`, `0.1877 + slope`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quantity {
    pub value: f64,
    pub dim: Option<Dimension>,
}

impl Quantity {
    /// The sum's dimension: both the same (an angle and a plain number make an angle).
    pub fn add(self, r: Self, minus: bool) -> Result<Self, String> {
        let value = if minus {
            self.value - r.value
        } else {
            self.value + r.value
        };
        let dim = match (self.dim, r.dim) {
            (None, d) | (d, None) => d,
            (Some(a), Some(b)) if a.accepts(b) => Some(a),
            (Some(a), Some(b)) if b.accepts(a) => Some(b),
            (Some(a), Some(b)) => {
                return Err(format!(
                    "`{}` between {} and {}",
                    if minus { '-' } else { '+' },
                    a.name(),
                    b.name()
                ))
            }
        };
        Ok(Self { value, dim })
    }

    /// The product's (or quotient's) dimension.
    pub fn mul(self, r: Self, divide: bool) -> Self {
        let value = if divide {
            self.value / r.value
        } else {
            self.value * r.value
        };
        let r_dim = r.dim.map(|d| if divide { d.pow(-1.0) } else { d });
        let dim = match (self.dim, r_dim) {
            (None, d) | (d, None) => d,
            (Some(a), Some(b)) => Some(a.times(b)),
        };
        Self { value, dim }
    }

    /// The power's dimension: the exponent must be a plain number (its value is known: the
    /// spec's defaults).
    pub fn pow(self, e: Self) -> Result<Self, String> {
        if let Some(d) = e.dim {
            if d != Dimension::DIMENSIONLESS {
                return Err(format!("an exponent is a plain number, not {}", d.name()));
            }
        }
        Ok(Self {
            value: self.value.powf(e.value),
            dim: self.dim.map(|d| d.pow(e.value)),
        })
    }
}
