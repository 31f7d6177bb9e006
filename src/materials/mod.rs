//! Constitutive models, one per file, and the registry that names them to scenes.
//!
//! A material's file holds all of it: its scene entry (a serde struct, the schema, with the
//! checks of [`SceneMaterial::model`]), the model ([`Material`]) and the model's internal
//! state ([`Material::State`], one column of the points that carry it). The registry
//! ([`materials!`](crate::materials!)) lists the scene entries; the scene's material enum
//! ([`MaterialSpec`]), the model enum ([`MaterialModel`]) and the list of point columns that
//! the spatial sort and checkpoints move are derived from it. A new material is its file and
//! one line there.
//!
//! The stress update system applies the Jaumann rotation first and then hands each point's
//! strain increment to its material, so a material only integrates σ̇ = C : ε̇ (eq. 7) in a
//! fixed frame.

mod linear_elastic;
mod modified_cam_clay;
mod mohr_coulomb;
mod mohr_coulomb_softening;

pub use linear_elastic::{LinearElastic, LinearElasticSpec};
pub use modified_cam_clay::{
    CamClayState, Drainage, ModifiedCamClay, ModifiedCamClaySpec, Preconsolidation, MIN_STIFFNESS_PRESSURE,
};
pub use mohr_coulomb::{MohrCoulomb, MohrCoulombSpec, PlasticStrain, Return};
pub use mohr_coulomb_softening::{MohrCoulombSoftening, MohrCoulombSofteningSpec, SofteningStrain};

use crate::error::Refusal;
use crate::infra::lanes::{Lanes, LANES};
use crate::tensor::{Sym, Sym3, Sym3x4};
use hecs::Archetype;
use serde::{de::DeserializeOwned, Deserialize, Serialize};
use std::any::TypeId;
use std::fmt::Debug;

/// The material registry: calls `$mac!([args] Variant(SceneEntry), ...)` with every material
/// a scene can name, as `Variant(field: value, ...)` in its `materials` map. A new material is
/// one line here (its file and its [`SceneMaterial`] impl do the rest).
#[macro_export]
#[doc(hidden)]
macro_rules! materials {
    ([$($mac:tt)*] [$($arg:tt)*]) => {
        $($mac)*! {[$($arg)*]
            LinearElastic($crate::materials::LinearElasticSpec),
            MohrCoulomb($crate::materials::MohrCoulombSpec),
            MohrCoulombSoftening($crate::materials::MohrCoulombSofteningSpec),
            ModifiedCamClay($crate::materials::ModifiedCamClaySpec),
        }
    };
}

/// A model's internal state at a point, beyond its stress: `()` for a model without one. It
/// is a point column (only on points whose material has it), moved by the spatial sort and
/// saved by checkpoints byte for byte, so it must be a plain struct of `f64` without padding.
pub trait MaterialState: bytemuck::Pod + Default + PartialEq + Debug + Send + Sync {
    /// Accumulated equivalent plastic strain (dimensionless), written as `plastic_strain`.
    fn plastic_strain(&self) -> f64;
    /// True when every value is finite.
    fn is_finite(&self) -> bool;
    /// u (Pa, compression positive): the excess pore pressure a model with undrained water
    /// holds in the point's stress column, which is then σ′ − u I; 0 by default.
    fn excess_pore_pressure(&self) -> f64 {
        0.0
    }
    /// Sets u (Pa) in a state that holds undrained water; the caller moves the point's
    /// stress column with it (`systems/pore_pressure_field.rs`). Nothing for a state
    /// without water, which is never asked.
    fn set_excess_pore_pressure(&mut self, _u: f64) {}
    /// The state's other values by name (units in the model's docs), for element tests and
    /// output: none by default.
    fn fields(&self) -> Vec<(&'static str, f64)> {
        Vec::new()
    }
    /// Why this state has no physical meaning (a clay with no voids left), or `None`: set-up
    /// refuses such a start and an element test stops at it. None by default.
    fn fault(&self) -> Option<String> {
        None
    }
}

impl MaterialState for () {
    fn plastic_strain(&self) -> f64 {
        0.0
    }
    fn is_finite(&self) -> bool {
        true
    }
}

/// A constitutive model.
pub trait Material: Send + Sync {
    /// The internal state each point carries, `()` when none.
    type State: MaterialState;
    /// Mass density ρ (kg/m³).
    fn density(&self) -> f64;
    /// P-wave (constrained) modulus M = K + 4G/3 (Pa), for the wave speed and time step.
    fn p_wave_modulus(&self) -> f64;
    /// Integrates the stress over one strain increment `de` (dimensionless, already in the
    /// rotated frame), updating the point's state.
    fn update(&self, stress: &mut Sym3, de: &Sym3, state: &mut Self::State);
    /// [`Material::update`] for four points of this material side by side, one per lane,
    /// with the same bits for each as `update` would give it. By default lane by lane; linear
    /// elasticity does all four at once; Mohr-Coulomb tests all four for yield in lanes and
    /// returns one by one only the points that fail the test.
    #[inline(always)]
    fn update4(&self, stress: &mut Sym3x4, de: &Sym3x4, state: [&mut Self::State; LANES]) {
        update_lane_by_lane(stress, de, state, |_, s, de, st| self.update(s, de, st));
    }
    /// Whether the model's strength admits `stress` (Pa) at a point of state `state`: inside
    /// or on its yield surface. Always, for a model without strength. The cell means against
    /// locking ask it after they move a point's mean stress (`systems/cell_mean.rs`).
    fn admits(&self, _stress: &Sym3, _state: &Self::State) -> bool {
        true
    }
    /// True when the model holds undrained pore water in its state (its points' stress
    /// columns hold σ′ − u I): their pore pressure is then a cell field
    /// (`systems/pore_pressure_field.rs`).
    fn holds_water(&self) -> bool {
        false
    }
    /// The undrained shear strength s_u (Pa) of a point at `stress` (Pa, the point's stress
    /// column) and `state`: what a penetrometer's N_kt divides by (`rigid/cpt.rs`). `None`
    /// for a model without one (an elastic or frictional soil).
    fn undrained_strength(&self, _stress: &Sym3, _state: &Self::State) -> Option<f64> {
        None
    }
    /// The shear strength of the soil on a plane through a point at `stress` (Pa) and
    /// `state`, τ ≤ c + σ_n tan φ with σ_n the plane's normal pressure: (c in Pa, tan φ).
    /// What a `Rough` interface beside the point can carry (`rigid/soil_strength.rs`).
    /// `None` for a model without strength (elastic): the interface does not slip.
    fn plane_strength(&self, _stress: &Sym3, _state: &Self::State) -> Option<(f64, f64)> {
        None
    }
    /// [`Material::plane_strength`] when it is the same at every stress and state (c in Pa,
    /// tan φ): a `Rough` interface on a soil of one such material takes it without summing
    /// the points beside it. `None` where the strength varies, or where there is none.
    fn constant_strength(&self) -> Option<(f64, f64)> {
        None
    }
    /// Why a point of this model may not start at `stress` (Pa, its stress column as set-up
    /// gives it), or `None` where it may: a start outside the range the model was set for
    /// (its stiffness past the time step's, a state with no physical meaning). Set-up
    /// refuses such a start at the body's `initial_stress`.
    fn start_fault(&self, _stress: &Sym3) -> Option<String> {
        None
    }
}

/// A material as a scene gives it: the serde struct is its schema.
pub trait SceneMaterial: Clone + PartialEq + Debug + Serialize + DeserializeOwned {
    /// The model it describes.
    type Model: Material + Clone + PartialEq + Debug;
    /// The model, each field checked; an error names the field (through `at`, which makes a
    /// field's dotted path) and the rule it breaks.
    fn model(&self, at: &dyn Fn(&str) -> String) -> Result<Self::Model, Refusal>;
    /// Divides the strength by `factor` for a strength-reduction analysis (c and tan φ, and
    /// what else the model holds as strength); false for a model without strength.
    fn reduce_strength(&mut self, _factor: f64) -> bool {
        false
    }
    /// The largest dilatancy angle ψ the model's plastic flow takes (degrees): 0 for an
    /// elastic model or isochoric flow. Volumetric smoothing is refused where it is above 0.
    fn dilatancy_angle(&self) -> f64 {
        0.0
    }
    /// The field whose value sets the model's P-wave speed, named when that speed is
    /// refused (too fast for a stage, not finite): Young's modulus by default.
    fn stiffness_field(&self) -> &'static str {
        "youngs_modulus"
    }
    /// True when the model holds undrained pore water in its state (the point's stress
    /// column then holds σ′ − u I). The cell means against locking are refused there.
    fn holds_water(&self) -> bool {
        false
    }
}

/// The largest Young's modulus a scene may give (Pa): a thousand times diamond's
/// (1.2e12 Pa), so stiffer than any ground or structure. Far above it, the products of
/// moduli in a plastic return overflow and the stress becomes NaN.
pub const MAX_MODULUS: f64 = 1e15;

/// Something done with one state type, chosen at run time (see [`visit_states`] and
/// [`MaterialModel::visit_state`]).
pub trait StateVisitor {
    /// Called with the state type `S`.
    fn visit<S: MaterialState>(&mut self);
}

/// Calls `update(lane, stress, de, state)` with each lane's stress, strain increment and
/// state in turn, and puts the stresses back into their lanes.
#[inline(always)]
pub fn update_lane_by_lane<S>(
    stress: &mut Sym3x4,
    de: &Sym3x4,
    state: [&mut S; LANES],
    mut update: impl FnMut(usize, &mut Sym3, &Sym3, &mut S),
) {
    let (mut s, de) = (stress.lanes(), de.lanes());
    for (lane, ((s, de), st)) in s.iter_mut().zip(&de).zip(state).enumerate() {
        update(lane, s, de, st);
    }
    *stress = Sym3x4::gather(|l| s[l]);
}

/// `state` as a `T`, when `S` is `T`.
#[inline(always)]
fn same_type<S: MaterialState, T: MaterialState>(state: &mut S) -> Option<&mut T> {
    // Two constants once monomorphised: the test costs nothing per point.
    if TypeId::of::<S>() == TypeId::of::<T>() {
        // SAFETY: `S` and `T` have the same `TypeId`, so they are the same type and the
        // pointer is a valid, unique `&mut T` for the borrow's lifetime.
        Some(unsafe { &mut *(state as *mut S).cast::<T>() })
    } else {
        None
    }
}

/// Four states of type `S` as `T`s, when `S` is `T`.
#[inline(always)]
fn same_types<S: MaterialState, T: MaterialState>(state: [&mut S; LANES]) -> Option<[&mut T; LANES]> {
    if TypeId::of::<S>() == TypeId::of::<T>() {
        Some(state.map(|s| same_type::<S, T>(s).expect("the same type")))
    } else {
        None
    }
}

/// The default state of a model that has none; a model with state reached here is a point
/// spawned without its material's state column, which the scene's set-up never does.
#[inline(always)]
fn stateless<M: Material>() -> M::State {
    assert!(
        std::mem::size_of::<M::State>() == 0,
        "a point's state column is not its material's {}: a point must be spawned with the \
         state of every material it takes",
        std::any::type_name::<M::State>()
    );
    M::State::default()
}

/// Derives the scene's material enum, the model enum and their dispatch from the registry.
macro_rules! define_materials {
    ([] $($variant:ident($spec:ty)),* $(,)?) => {
        /// A material, by model, as a scene's `materials` map gives it:
        /// `Model(field: value, ...)`.
        #[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
        pub enum MaterialSpec {
            $(
                #[doc = concat!("See [`", stringify!($variant), "`](", stringify!($spec), ").")]
                $variant($spec),
            )*
        }

        /// The model of each material a scene can name.
        #[derive(Clone, Debug, PartialEq)]
        pub enum MaterialModel {
            $(
                #[doc = concat!("See [`", stringify!($variant), "`](", stringify!($spec), ").")]
                $variant(<$spec as SceneMaterial>::Model),
            )*
        }

        impl MaterialSpec {
            /// The model, each field checked, and its wave speed; an error names the field
            /// (through `at`) and the rule.
            pub fn model(&self, at: &dyn Fn(&str) -> String) -> Result<MaterialModel, Refusal> {
                let model = match self {
                    $(MaterialSpec::$variant(s) => MaterialModel::$variant(s.model(at)?),)*
                };
                // The P-wave speed sets the time step: it must be a finite number > 0 (an E
                // near the largest double overflows M, a density near the smallest overflows
                // M/ρ).
                let speed = (model.p_wave_modulus() / model.density()).sqrt();
                if !(speed > 0.0 && speed.is_finite()) {
                    return Err(Refusal::new(
                        at(self.stiffness_field()),
                        format!(
                            "M = {} Pa with ρ = {} kg/m³ gives a P-wave speed of {speed} m/s, not \
                             a finite number > 0",
                            model.p_wave_modulus(),
                            model.density()
                        ),
                    ));
                }
                Ok(model)
            }

            /// Divides the strength by `factor` (see [`SceneMaterial::reduce_strength`]).
            pub fn reduce_strength(&mut self, factor: f64) -> bool {
                match self {
                    $(MaterialSpec::$variant(s) => s.reduce_strength(factor),)*
                }
            }

            /// The largest dilatancy angle (degrees; see [`SceneMaterial::dilatancy_angle`]).
            pub fn dilatancy_angle(&self) -> f64 {
                match self {
                    $(MaterialSpec::$variant(s) => s.dilatancy_angle(),)*
                }
            }

            /// The field that sets its P-wave speed (see [`SceneMaterial::stiffness_field`]).
            pub fn stiffness_field(&self) -> &'static str {
                match self {
                    $(MaterialSpec::$variant(s) => s.stiffness_field(),)*
                }
            }

            /// Whether it holds undrained water (see [`SceneMaterial::holds_water`]).
            pub fn holds_water(&self) -> bool {
                match self {
                    $(MaterialSpec::$variant(s) => s.holds_water(),)*
                }
            }
        }

        impl MaterialModel {
            /// Mass density ρ (kg/m³).
            pub fn density(&self) -> f64 {
                match self {
                    $(MaterialModel::$variant(m) => m.density(),)*
                }
            }

            /// P-wave modulus M (Pa).
            pub fn p_wave_modulus(&self) -> f64 {
                match self {
                    $(MaterialModel::$variant(m) => m.p_wave_modulus(),)*
                }
            }

            /// The model's name, as a scene writes it.
            pub fn name(&self) -> &'static str {
                match self {
                    $(MaterialModel::$variant(_) => stringify!($variant),)*
                }
            }

            /// Calls `v` with this model's state type.
            pub fn visit_state(&self, v: &mut impl StateVisitor) {
                match self {
                    $(MaterialModel::$variant(_) => v.visit::<<<$spec as SceneMaterial>::Model as Material>::State>(),)*
                }
            }

            /// Whether it holds undrained water in its state (see [`Material::holds_water`]).
            pub fn holds_water(&self) -> bool {
                match self {
                    $(MaterialModel::$variant(m) => m.holds_water(),)*
                }
            }

            /// Its strength when the same at every stress and state (see
            /// [`Material::constant_strength`]).
            pub fn constant_strength(&self) -> Option<(f64, f64)> {
                match self {
                    $(MaterialModel::$variant(m) => m.constant_strength(),)*
                }
            }

            /// Why a point may not start at `stress` (see [`Material::start_fault`]).
            pub fn start_fault(&self, stress: &Sym3) -> Option<String> {
                match self {
                    $(MaterialModel::$variant(m) => m.start_fault(stress),)*
                }
            }

            /// The name of this model's state type, `None` when it has no state.
            pub fn state_name(&self) -> Option<&'static str> {
                struct Name(Option<&'static str>);
                impl StateVisitor for Name {
                    fn visit<S: MaterialState>(&mut self) {
                        self.0 = (std::mem::size_of::<S>() > 0).then(std::any::type_name::<S>);
                    }
                }
                let mut name = Name(None);
                self.visit_state(&mut name);
                name.0
            }

            /// Bytes of this model's state a point.
            pub fn state_bytes(&self) -> usize {
                struct Size(usize);
                impl StateVisitor for Size {
                    fn visit<S: MaterialState>(&mut self) {
                        self.0 = std::mem::size_of::<S>();
                    }
                }
                let mut size = Size(0);
                self.visit_state(&mut size);
                size.0
            }

            /// [`Material::update`] of one point whose state column is of type `S`.
            #[inline(always)]
            pub fn update<S: MaterialState>(&self, stress: &mut Sym3, de: &Sym3, state: &mut S) {
                // Static dispatch on the enum keeps the per-point call inlinable.
                match self {
                    // A model's own state, or a throw-away one for a model without state
                    // (an elastic stage of a body that carries plastic state keeps it).
                    $(MaterialModel::$variant(m) => match same_type(state) {
                        Some(own) => m.update(stress, de, own),
                        None => m.update(stress, de, &mut stateless::<<$spec as SceneMaterial>::Model>()),
                    },)*
                }
            }

            /// [`Material::admits`] for a point whose state column is of type `S`.
            pub fn admits<S: MaterialState>(&self, stress: &Sym3, state: &S) -> bool {
                let mut own = *state;
                match self {
                    $(MaterialModel::$variant(m) => match same_type(&mut own) {
                        Some(own) => m.admits(stress, own),
                        None => m.admits(stress, &stateless::<<$spec as SceneMaterial>::Model>()),
                    },)*
                }
            }

            /// [`Material::undrained_strength`] of a point whose state column is of type `S`.
            pub fn undrained_strength<S: MaterialState>(&self, stress: &Sym3, state: &S) -> Option<f64> {
                let mut own = *state;
                match self {
                    $(MaterialModel::$variant(m) => match same_type(&mut own) {
                        Some(own) => m.undrained_strength(stress, own),
                        None => m.undrained_strength(stress, &stateless::<<$spec as SceneMaterial>::Model>()),
                    },)*
                }
            }

            /// [`Material::plane_strength`] of a point whose state column is of type `S`.
            pub fn plane_strength<S: MaterialState>(&self, stress: &Sym3, state: &S) -> Option<(f64, f64)> {
                let mut own = *state;
                match self {
                    $(MaterialModel::$variant(m) => match same_type(&mut own) {
                        Some(own) => m.plane_strength(stress, own),
                        None => m.plane_strength(stress, &stateless::<<$spec as SceneMaterial>::Model>()),
                    },)*
                }
            }

            /// [`Material::update4`] of four points of this material whose state column is of
            /// type `S`.
            #[inline(always)]
            pub fn update4<S: MaterialState>(&self, stress: &mut Sym3x4, de: &Sym3x4, state: [&mut S; LANES]) {
                match self {
                    // Calls, not closures: the model's update is inlined into the loop.
                    $(MaterialModel::$variant(m) => match same_types(state) {
                        Some(own) => m.update4(stress, de, own),
                        None => {
                            let mut none = [stateless::<<$spec as SceneMaterial>::Model>(); LANES];
                            m.update4(stress, de, none.each_mut())
                        }
                    },)*
                }
            }
        }

        /// Calls `v` with the state type of every registered material (`()` included).
        pub fn visit_states(v: &mut impl StateVisitor) {
            $(v.visit::<<<$spec as SceneMaterial>::Model as Material>::State>();)*
        }
    };
}

materials!([define_materials] []);

/// Isotropic elastic stiffness from Young's modulus and Poisson's ratio.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Elasticity {
    /// Shear modulus G (Pa).
    pub shear: f64,
    /// Lamé's first parameter λ (Pa).
    pub lambda: f64,
}

impl Elasticity {
    /// From Young's modulus E (Pa) and Poisson's ratio ν.
    pub fn new(youngs_modulus: f64, poisson_ratio: f64) -> Self {
        let (e, nu) = (youngs_modulus, poisson_ratio);
        Elasticity {
            shear: e / (2.0 * (1.0 + nu)),
            lambda: e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
        }
    }

    /// Checked E (Pa, in (0, [`MAX_MODULUS`]]) and ν (in [0, 0.5)) with the density ρ (kg/m³, > 0) of the same
    /// scene entry; an error names the field (through `at`) and the rule.
    pub fn checked(
        at: &dyn Fn(&str) -> String,
        density: f64,
        youngs_modulus: f64,
        poisson_ratio: f64,
    ) -> Result<Self, Refusal> {
        let positive = |x: f64| x > 0.0 && x.is_finite();
        if !positive(density) {
            return Err(Refusal::new(
                at("density"),
                format!("must be > 0 kg/m³, found {density}"),
            ));
        }
        if !(positive(youngs_modulus) && youngs_modulus <= MAX_MODULUS) {
            return Err(Refusal::new(
                at("youngs_modulus"),
                format!("must be > 0 Pa and at most {MAX_MODULUS:e} Pa, found {youngs_modulus:e}"),
            ));
        }
        if !(0.0..0.5).contains(&poisson_ratio) {
            return Err(Refusal::new(
                at("poisson_ratio"),
                format!("must be in [0, 0.5), found {poisson_ratio}"),
            ));
        }
        Ok(Elasticity::new(youngs_modulus, poisson_ratio))
    }

    /// Bulk modulus K (Pa).
    pub fn bulk(&self) -> f64 {
        self.lambda + 2.0 / 3.0 * self.shear
    }

    /// P-wave modulus M = λ + 2G (Pa).
    pub fn p_wave(&self) -> f64 {
        self.lambda + 2.0 * self.shear
    }

    /// Stress increment C : de, of one point or four in lanes.
    #[inline(always)]
    pub fn stress_increment<T: Lanes>(&self, de: &Sym<T>) -> Sym<T> {
        let vol = T::splat(self.lambda) * de.trace();
        let g2 = T::splat(2.0 * self.shear);
        Sym {
            xx: vol + g2 * de.xx,
            yy: vol + g2 * de.yy,
            zz: vol + g2 * de.zz,
            xy: g2 * de.xy,
            yz: g2 * de.yz,
            zx: g2 * de.zx,
        }
    }
}

/// Something done with the points of one archetype and their material state column,
/// whatever its type ([`with_state_column`]).
pub trait WithStates {
    /// `states`: the state column of `arch`, `None` when its points carry no state.
    fn with<S: MaterialState>(&mut self, arch: &Archetype, states: Option<&[S]>);
}

/// Calls `user` once with the state column of `arch` (the first registered state type of
/// some size it holds), or with none.
pub fn with_state_column(arch: &Archetype, user: &mut impl WithStates) {
    struct Find<'a, U>(&'a Archetype, &'a mut U, bool);
    impl<U: WithStates> StateVisitor for Find<'_, U> {
        fn visit<S: MaterialState>(&mut self) {
            if self.2 || std::mem::size_of::<S>() == 0 {
                return;
            }
            if let Some(states) = self.0.get::<&S>() {
                self.1.with(self.0, Some(&states));
                self.2 = true;
            }
        }
    }
    let mut find = Find(arch, user, false);
    visit_states(&mut find);
    if !find.2 {
        find.1.with::<()>(arch, None);
    }
}

/// Appends the accumulated plastic strain of each point of `arch` to `out`, in row order:
/// from the column of its material's state, 0 where the points carry no state.
pub fn extend_plastic_strain(arch: &Archetype, out: &mut Vec<f64>) {
    struct Extend<'a>(&'a Archetype, &'a mut Vec<f64>, bool);
    impl StateVisitor for Extend<'_> {
        fn visit<S: MaterialState>(&mut self) {
            if let (false, Some(c)) = (self.2, self.0.get::<&S>()) {
                self.1.extend(c.iter().map(S::plastic_strain));
                self.2 = true;
            }
        }
    }
    let mut e = Extend(arch, out, false);
    visit_states(&mut e);
    if !e.2 {
        out.resize(out.len() + arch.len() as usize, 0.0);
    }
}

/// The names of the state fields ([`MaterialState::fields`]) of the points of `arch`, none
/// when its points carry no state or a state without fields.
pub fn state_field_names(arch: &Archetype) -> Vec<&'static str> {
    struct Names<'a>(&'a Archetype, Vec<&'static str>);
    impl StateVisitor for Names<'_> {
        fn visit<S: MaterialState>(&mut self) {
            if self.1.is_empty() && self.0.has::<S>() {
                self.1 = S::default().fields().into_iter().map(|(n, _)| n).collect();
            }
        }
    }
    let mut n = Names(arch, Vec::new());
    visit_states(&mut n);
    n.1
}

/// Appends to `out[k]` the state field `names[k]` of each point of `arch`, in row order: 0
/// where the point's state has no such field.
pub fn extend_state_fields(arch: &Archetype, names: &[&'static str], out: &mut [Vec<f64>]) {
    struct Extend<'a>(&'a Archetype, &'a [&'static str], &'a mut [Vec<f64>], bool);
    impl StateVisitor for Extend<'_> {
        fn visit<S: MaterialState>(&mut self) {
            if let (false, Some(c)) = (self.3, self.0.get::<&S>()) {
                for s in c.iter() {
                    let f = s.fields();
                    for (k, name) in self.1.iter().enumerate() {
                        let v = f.iter().find(|(n, _)| n == name).map_or(0.0, |(_, v)| *v);
                        self.2[k].push(v);
                    }
                }
                self.3 = true;
            }
        }
    }
    let mut e = Extend(arch, names, out, false);
    visit_states(&mut e);
    if !e.3 {
        for o in out.iter_mut() {
            o.resize(o.len() + arch.len() as usize, 0.0);
        }
    }
}

/// The rows of `arch` whose material state has no physical meaning, each with why
/// ([`MaterialState::fault`]); none allocates nothing.
pub fn state_faults(arch: &Archetype) -> Vec<(usize, String)> {
    struct Find<'a>(&'a Archetype, Vec<(usize, String)>);
    impl StateVisitor for Find<'_> {
        fn visit<S: MaterialState>(&mut self) {
            if let Some(c) = self.0.get::<&S>() {
                let faults = c.iter().enumerate().filter_map(|(r, s)| Some((r, s.fault()?)));
                self.1.extend(faults);
            }
        }
    }
    let mut f = Find(arch, Vec::new());
    visit_states(&mut f);
    f.1
}

/// The first row of `arch` whose material state holds a value that is not finite.
pub fn first_non_finite_state(arch: &Archetype) -> Option<usize> {
    struct Find<'a>(&'a Archetype, Option<usize>);
    impl StateVisitor for Find<'_> {
        fn visit<S: MaterialState>(&mut self) {
            if let (None, Some(c)) = (self.1, self.0.get::<&S>()) {
                self.1 = c.iter().position(|s| !s.is_finite());
            }
        }
    }
    let mut f = Find(arch, None);
    visit_states(&mut f);
    f.1
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_registered_state_is_its_own_type_or_none() {
        // The spatial sort and checkpoints move each listed state column once: two models
        // sharing a state type would move it twice.
        struct Seen(Vec<TypeId>);
        impl StateVisitor for Seen {
            fn visit<S: MaterialState>(&mut self) {
                if std::mem::size_of::<S>() > 0 {
                    assert!(
                        !self.0.contains(&TypeId::of::<S>()),
                        "{} is the state of two models",
                        std::any::type_name::<S>()
                    );
                    self.0.push(TypeId::of::<S>());
                }
            }
        }
        visit_states(&mut Seen(Vec::new()));
    }

    #[test]
    fn an_elastic_stage_leaves_a_plastic_state_as_it_was() {
        let elastic = MaterialSpec::LinearElastic(LinearElasticSpec {
            density: 2000.0,
            youngs_modulus: 1e7,
            poisson_ratio: 0.3,
        })
        .model(&|f| f.to_string())
        .unwrap();
        let mut state = PlasticStrain(0.25);
        let mut stress = Sym3::ZERO;
        elastic.update(&mut stress, &Sym3::diagonal(1e-3, 0.0, 0.0), &mut state);
        assert_eq!(state, PlasticStrain(0.25));
        assert!(stress.xx > 0.0);
    }
}
