//! How one laser beam comes back — or does not — from what it meets (thesis §3.2.1, Fig. 3.1–3.2).
//!
//! A time-of-flight laser reports half the path its pulse travelled before coming back. What the
//! pulse meets decides what that path is:
//!
//! - **any surface at grazing incidence** sends the pulse away: nothing comes back, and the LMS
//!   reports its maximum;
//! - **matte** surfaces (paint, plaster, wood) scatter the pulse back at any other incidence;
//! - **black**, low-reflectivity surfaces return it seen head-on but lose it at oblique incidence
//!   (the thesis's black, slightly wavy door): the chance of a return falls linearly from
//!   `black_full` to none at `black_lost`;
//! - **glass** returns the pulse itself near the normal; otherwise, by chance, it is a window (the
//!   pulse goes on) or a mirror (the pulse reflects, reaches another object and comes back the same
//!   way, so the reading is the glass distance plus the distance beyond: objects, the robot
//!   itself included, appear behind the glass);
//! - **metal** and mirrors return the pulse near the normal and reflect it otherwise.
//!
//! A pulse that has been reflected or transmitted `max_bounces` times, or has travelled the
//! laser's maximum range, is lost.

use crate::config::{Material, Optics};
use crate::rng::SimRng;
use crate::world::{Beyond, FanCast, Hit, Surface, WorldMap};
use parry2d::math::{Pose, Vector};
use parry2d::query::{Ray, RayCast};
use parry2d::shape::Ball;
use rand::RngExt;

impl Optics {
    /// The thresholds as cosines of the incidence, computed once for many pulses.
    pub fn prepared(&self) -> PreparedOptics {
        PreparedOptics {
            optics: *self,
            cos_grazing: self.grazing.cos(),
            cos_glass_return: self.glass_return.cos(),
            cos_metal_return: self.metal_return.cos(),
            cos_black_full: self.black_full.cos(),
            cos_black_lost: self.black_lost.cos(),
        }
    }
}

/// [`Optics`] with the cosines of its thresholds, so a pulse compares cosines instead of taking
/// an arc cosine at every surface.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct PreparedOptics {
    optics: Optics,
    cos_grazing: f64,
    cos_glass_return: f64,
    cos_metal_return: f64,
    cos_black_full: f64,
    cos_black_lost: f64,
}

impl PreparedOptics {
    /// The chance that a black surface met at incidence cosine `cos_in` returns the pulse:
    /// certain within `black_full` of the normal, none beyond `black_lost`, falling linearly
    /// with the angle between.
    #[inline]
    fn black_return(&self, cos_in: f64) -> f64 {
        let optics = &self.optics;
        let span = optics.black_lost - optics.black_full;
        if cos_in >= self.cos_black_full {
            1.0
        } else if cos_in <= self.cos_black_lost {
            0.0
        } else if span > 0.0 {
            ((optics.black_lost - cos_in.acos()) / span).clamp(0.0, 1.0)
        } else {
            f64::from(u8::from(cos_in.acos() < optics.black_full))
        }
    }
}

/// A round obstacle that moves: the robot's own body, a vertical cylinder from the floor, which
/// reflected pulses can meet.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Disc {
    /// Centre, world frame, metres.
    pub center: [f64; 2],
    /// Radius, metres.
    pub radius: f64,
    /// Height of the top, metres.
    pub height: f64,
}

/// What the receiver gets back from one pulse.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum Echo {
    /// The pulse came back after travelling this far one way, metres.
    Range(f64),
    /// Nothing came back.
    Lost,
}

/// What the pulse met next.
#[derive(Copy, Clone, Debug)]
struct Contact {
    distance: f64,
    normal: [f64; 3],
    material: Material,
    /// The vertical face it met, if it met one.
    face: Option<usize>,
}

/// What the second legs of one scan's beams share: the face the last one met, where the next
/// one's search stops at the latest ([`WorldMap::cast_near`]), and for each face first legs
/// ended on, the faces the legs leaving it can meet ([`WorldMap::faces_beyond`]), listed
/// once a second leg leaves it. Start a new one for each scan: it holds only for beams from
/// one origin.
#[derive(Clone, Debug, Default)]
pub struct Legs {
    hint: Option<usize>,
    cones: Vec<Cone>,
    faces: Vec<Beyond>,
}

impl Legs {
    /// Forgets the last scan's, keeping the buffers.
    pub fn clear(&mut self) {
        self.hint = None;
        self.cones.clear();
        self.faces.clear();
    }
}

/// The legs leaving one face of a scan: how they are cast.
#[derive(Copy, Clone, Debug)]
struct Cone {
    /// The face left and whether through it.
    key: (u32, bool),
    listing: Listing,
}

/// How the legs leaving a face are cast.
#[derive(Copy, Clone, Debug)]
enum Listing {
    /// One has left it, down the walk of the plan's grid: a third of the faces a scan's
    /// legs leave serve one leg only, for which listing the cone's faces costs about four walks.
    Once,
    /// Among `faces[from..to]` of [`Legs`], from `apex`: the laser's origin, or its image
    /// behind the face, in the plan.
    Among { apex: [f64; 2], from: u32, to: u32 },
    /// Down the walk: no cone holds them (the laser on the face's line, or too many faces).
    Walk,
}

/// Follows one pulse from `origin` along the unit direction `dir`.
///
/// The first leg starts inside the robot, so the robot's `body` is only seen by reflected or
/// transmitted legs.
pub fn trace(
    map: &WorldMap,
    optics: &Optics,
    body: Option<Disc>,
    origin: [f64; 3],
    dir: [f64; 3],
    max_range: f64,
    rng: &mut SimRng,
) -> Echo {
    Pulses::with_optics(map, optics, body, max_range).trace(origin, dir, rng)
}

/// What is fixed for all the pulses of a scan: the world with its optics prepared, the robot's
/// body and the range.
#[derive(Copy, Clone)]
pub struct Pulses<'a> {
    map: &'a WorldMap,
    prepared: PreparedOptics,
    body: Option<Disc>,
    /// Other robots, which every leg can meet.
    others: &'a [Disc],
    max_range: f64,
    /// Every leg cast down the world's tree ([`WorldMap::cast_down_tree`]), as the reference.
    down_tree: bool,
}

impl<'a> Pulses<'a> {
    /// Pulses in `map` with its own optics.
    pub fn new(map: &'a WorldMap, body: Option<Disc>, max_range: f64) -> Self {
        Self::with_optics(map, map.optics(), body, max_range)
    }

    /// Pulses in `map` answered by `optics`.
    pub fn with_optics(
        map: &'a WorldMap,
        optics: &Optics,
        body: Option<Disc>,
        max_range: f64,
    ) -> Self {
        Pulses {
            map,
            prepared: optics.prepared(),
            body,
            others: &[],
            max_range,
            down_tree: false,
        }
    }

    /// The same pulses with every leg cast down the world's tree: the reference the walk of
    /// the plan's grid and the sweep are tested against.
    pub fn down_tree(self) -> Self {
        Pulses {
            down_tree: true,
            ..self
        }
    }

    /// The same pulses among other robots' bodies, which every leg can meet.
    pub fn among(self, others: &'a [Disc]) -> Self {
        Pulses { others, ..self }
    }

    /// Follows one pulse from `origin` along the unit direction `dir`.
    pub fn trace(&self, origin: [f64; 3], dir: [f64; 3], rng: &mut SimRng) -> Echo {
        let first = (self.max_range > 0.0)
            .then(|| self.cast(origin, dir, self.max_range, None))
            .flatten();
        self.trace_from(origin, dir, first.as_ref(), rng)
    }

    /// [`Pulses::trace`] with the first surface the pulse meets already known (`first`, what
    /// [`WorldMap::cast`] or [`WorldMap::cast_fan`] answer for the ray within the range): a
    /// scan casts all its beams' first legs in one sweep.
    #[inline]
    pub fn trace_from(
        &self,
        origin: [f64; 3],
        dir: [f64; 3],
        first: Option<&Hit>,
        rng: &mut SimRng,
    ) -> Echo {
        self.trace_near(origin, dir, first, &mut Legs::default(), rng)
    }

    /// [`Pulses::trace_from`] for one of a scan's beams in turn, all from `origin`: `legs`
    /// keeps what the scan's second legs share ([`Legs`]), so they are cast sooner, with the
    /// same echo.
    #[inline(always)]
    pub fn trace_near(
        &self,
        origin: [f64; 3],
        dir: [f64; 3],
        first: Option<&Hit>,
        legs: &mut Legs,
        rng: &mut SimRng,
    ) -> Echo {
        if self.max_range <= 0.0 {
            return Echo::Lost;
        }
        // The first leg starts inside the robot: only later legs can meet its body.
        let wall = first.map(|&hit| Contact::from(hit));
        match nearer_disc(wall, self.others.iter(), origin, dir, self.max_range) {
            Some(contact) => self.first_contact(origin, dir, contact, legs, rng),
            None => Echo::Lost,
        }
    }

    /// [`Pulses::trace_near`] for beam `k` of a scan's sweep `fan`, a call apart from the
    /// loop over the beams (those [`Pulses::off_face`] does not answer): it takes and gives
    /// back the generator by value, so the loop's own stays in registers, and its rarer work
    /// does not crowd the loop.
    #[inline(never)]
    pub fn beam_apart(
        &self,
        fan: &FanCast,
        k: usize,
        legs: &mut Legs,
        mut rng: SimRng,
    ) -> (Echo, SimRng) {
        let hit = fan.hit(self.map, k);
        let echo = self.trace_near(fan.origin(), fan.dir(k), hit.as_ref(), legs, &mut rng);
        (echo, rng)
    }

    /// Whether [`Pulses::off_face`] may answer a beam: no other robot to meet, a range to
    /// meet anything in.
    #[inline]
    pub fn plain(&self) -> bool {
        self.others.is_empty() && self.max_range > 0.0
    }

    /// [`Pulses::trace_near`] for a level beam (`dir[2]` zero) whose first surface is face
    /// `face`, `t` metres away, as a scan's sweep finds it: the same echo from the same draws,
    /// the hit built only for a pulse that goes on. Only for [`Pulses::plain`] pulses.
    #[inline(always)]
    pub fn off_face(
        &self,
        origin: [f64; 3],
        dir: [f64; 3],
        (t, face): (f64, usize),
        legs: &mut Legs,
        rng: &mut SimRng,
    ) -> Echo {
        // The hit's normal faces the ray: the cosine of the incidence is |dir · normal|.
        let normal = self.map.face_normal(face);
        let cos_in = (dir[0] * normal[0] + dir[1] * normal[1])
            .abs()
            .clamp(-1.0, 1.0);
        let material = self.map.faces()[face].material;
        match self.fate(material, cos_in, t, rng) {
            Fate::Ends(echo) => echo,
            fate => {
                let contact = Contact::from(self.map.face_hit(face, t, dir));
                self.go_on(origin, dir, (contact, fate), legs, rng)
            }
        }
    }

    /// The echo of a pulse from `origin` along `dir` whose first leg ends at `contact`: most
    /// end there (matte, black, grazing); the others go on.
    #[inline(always)]
    fn first_contact(
        &self,
        origin: [f64; 3],
        dir: [f64; 3],
        contact: Contact,
        legs: &mut Legs,
        rng: &mut SimRng,
    ) -> Echo {
        let travelled = contact.distance;
        match self.fate(contact.material, contact.cos_in(dir), travelled, rng) {
            Fate::Ends(echo) => echo,
            fate => self.go_on(origin, dir, (contact, fate), legs, rng),
        }
    }

    /// [`Pulses::onwards`], a call, given a copy of the generator: so a caller's own never
    /// has its address taken and can stay in registers instead of going through memory at
    /// every draw.
    #[inline(always)]
    fn go_on(
        &self,
        origin: [f64; 3],
        dir: [f64; 3],
        first: (Contact, Fate),
        legs: &mut Legs,
        rng: &mut SimRng,
    ) -> Echo {
        let mut copy = rng.clone();
        let echo = self.onwards(origin, dir, first, legs, &mut copy);
        *rng = copy;
        echo
    }

    /// What a surface of `material` met at incidence cosine `cos_in` (larger is nearer the
    /// normal), `travelled` metres along the pulse's path, does with the pulse. The draws
    /// come in a fixed order: none for matte or metal, one for black, one for glass met off
    /// its normal.
    #[inline(always)]
    fn fate(&self, material: Material, cos_in: f64, travelled: f64, rng: &mut SimRng) -> Fate {
        let prepared = &self.prepared;
        if cos_in <= prepared.cos_grazing {
            return Fate::Ends(Echo::Lost);
        }
        match material {
            Material::Matte => Fate::Ends(Echo::Range(travelled)),
            Material::Black => Fate::Ends(if rng.random_bool(prepared.black_return(cos_in)) {
                Echo::Range(travelled)
            } else {
                Echo::Lost
            }),
            Material::Glass if cos_in > prepared.cos_glass_return => {
                Fate::Ends(Echo::Range(travelled))
            }
            Material::Glass if rng.random_bool(prepared.optics.glass_transparent) => Fate::Through,
            Material::Metal if cos_in > prepared.cos_metal_return => {
                Fate::Ends(Echo::Range(travelled))
            }
            Material::Glass | Material::Metal => Fate::Reflects,
        }
    }

    /// What a leg from `origin` along `dir` meets first within `max`.
    #[inline]
    fn cast(&self, origin: [f64; 3], dir: [f64; 3], max: f64, hint: Option<usize>) -> Option<Hit> {
        let nearest = self.nearest(origin, dir, max, hint);
        self.map.fan_hit(origin, dir, max, nearest)
    }

    /// [`Pulses::cast`]'s nearest vertical face and its distance (`u32::MAX` for none): down
    /// the tree for the reference, else by the walk; what [`WorldMap::fan_hit`] builds the hit
    /// from.
    #[inline]
    fn nearest(
        &self,
        origin: [f64; 3],
        dir: [f64; 3],
        max: f64,
        hint: Option<usize>,
    ) -> (f64, u32) {
        if self.down_tree {
            self.map.nearest_down_tree(origin, dir, max)
        } else {
            self.map.nearest_near(origin, dir, max, hint)
        }
    }

    /// The nearest vertical face a second leg from `origin` along `dir` meets within `max`
    /// and its distance (`u32::MAX` for none), having left face `left` of the first surface
    /// — reflected, or through it (`through`) — of a beam from `apex`: among the faces the
    /// legs leaving that face can meet ([`Legs`]).
    fn nearest_second(
        &self,
        (origin, dir, max): ([f64; 3], [f64; 3], f64),
        apex: [f64; 3],
        (left, through): (usize, bool),
        legs: &mut Legs,
    ) -> (f64, u32) {
        if self.down_tree {
            return self.map.nearest_down_tree(origin, dir, max);
        }
        let key = (left as u32, through);
        let listing = match legs.cones.iter_mut().find(|c| c.key == key) {
            None => {
                legs.cones.push(Cone {
                    key,
                    listing: Listing::Once,
                });
                Listing::Once
            }
            Some(cone) => {
                if let Listing::Once = cone.listing {
                    cone.listing = self.cone_listing(apex, (left, through), &mut legs.faces);
                }
                cone.listing
            }
        };
        match listing {
            Listing::Among { apex, from, to } => {
                let faces = &legs.faces[from as usize..to as usize];
                self.map.nearest_among(origin, dir, max, apex, faces)
            }
            Listing::Once | Listing::Walk => self.map.nearest_near(origin, dir, max, legs.hint),
        }
    }

    /// The faces the legs leaving face `left` — reflected, or through it (`through`) — of
    /// beams from `apex` can meet, listed at the end of `faces`. Once or twice a scan: a
    /// call, kept out of the legs' path.
    #[inline(never)]
    fn cone_listing(
        &self,
        apex: [f64; 3],
        (left, through): (usize, bool),
        faces: &mut Vec<Beyond>,
    ) -> Listing {
        // The origin itself through a pane, its image behind a mirror.
        let mut from = [apex[0], apex[1]];
        if !through {
            let face = &self.map.faces()[left];
            let n = self.map.face_normal(left);
            let off = (from[0] - face.a[0]) * n[0] + (from[1] - face.a[1]) * n[1];
            from = [from[0] - 2.0 * off * n[0], from[1] - 2.0 * off * n[1]];
        }
        let start = faces.len();
        if self.map.faces_beyond(from, left, faces) {
            Listing::Among {
                apex: from,
                from: start as u32,
                to: faces.len() as u32,
            }
        } else {
            Listing::Walk
        }
    }

    /// The pulse's legs after its first: the first ended at `first`, on a surface that let
    /// the pulse through or reflected it (`Fate::Through`, `Fate::Reflects`). The second leg
    /// tries only the faces of its cone ([`Legs`]); the few legs after go through
    /// [`Pulses::later_legs`].
    #[inline(never)]
    fn onwards(
        &self,
        origin: [f64; 3],
        dir: [f64; 3],
        (first, fate): (Contact, Fate),
        legs: &mut Legs,
        rng: &mut SimRng,
    ) -> Echo {
        if self.prepared.optics.max_bounces == 0 {
            return Echo::Lost;
        }
        let mut pulse = Pulse {
            o: origin,
            d: dir,
            travelled: first.distance,
        };
        pulse.leave(&first, fate);
        let remaining = self.max_range - pulse.travelled;
        if remaining <= 0.0 {
            return Echo::Lost;
        }
        let (o, d) = (pulse.o, pulse.d);
        // Every way the leg is cast gives the nearest face as a pair in registers, and the hit
        // is built in one place: a hit written to memory on one path and read back whole after
        // the paths join stalled the load on the stores.
        let nearest = match first.face {
            Some(i) => {
                let through = fate == Fate::Through;
                let nearest = self.nearest_second((o, d, remaining), origin, (i, through), legs);
                if nearest.1 != u32::MAX {
                    legs.hint = Some(nearest.1 as usize);
                }
                nearest
            }
            None => self.nearest(o, d, remaining, legs.hint),
        };
        let wall = self
            .map
            .fan_hit(o, d, remaining, nearest)
            .map(Contact::from);
        let Some(contact) = nearer_disc(wall, self.body.iter().chain(self.others), o, d, remaining)
        else {
            return Echo::Lost;
        };
        pulse.travelled += contact.distance;
        match self.fate(contact.material, contact.cos_in(d), pulse.travelled, rng) {
            Fate::Ends(echo) => echo,
            fate => self.later_legs(pulse, (contact, fate), legs.hint, rng),
        }
    }

    /// The legs from the third on, each cast on its own: the second ended at `contact`, on a
    /// surface that let the pulse through or reflected it.
    #[inline(never)]
    fn later_legs(
        &self,
        mut pulse: Pulse,
        (mut contact, mut fate): (Contact, Fate),
        hint: Option<usize>,
        rng: &mut SimRng,
    ) -> Echo {
        for _ in 2..=self.prepared.optics.max_bounces {
            pulse.leave(&contact, fate);
            let remaining = self.max_range - pulse.travelled;
            if remaining <= 0.0 {
                return Echo::Lost;
            }
            let (o, d) = (pulse.o, pulse.d);
            let wall = self.cast(o, d, remaining, hint).map(Contact::from);
            let discs = self.body.iter().chain(self.others);
            let Some(next) = nearer_disc(wall, discs, o, d, remaining) else {
                return Echo::Lost;
            };
            contact = next;
            pulse.travelled += contact.distance;
            fate = self.fate(contact.material, contact.cos_in(d), pulse.travelled, rng);
            if let Fate::Ends(echo) = fate {
                return echo;
            }
        }
        Echo::Lost
    }
}

/// A pulse between surfaces: where its leg starts, its direction, and how far it has
/// travelled.
#[derive(Copy, Clone, Debug)]
struct Pulse {
    o: [f64; 3],
    d: [f64; 3],
    travelled: f64,
}

impl Pulse {
    /// Leaves the surface its leg met at `contact`: on from just beyond a pane
    /// (`Fate::Through`), or reflected from just in front of the surface (`Fate::Reflects`).
    #[inline(always)]
    fn leave(&mut self, contact: &Contact, fate: Fate) {
        let (o, d) = (self.o, self.d);
        let n = contact.normal;
        let along = d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
        let hit = [0, 1, 2].map(|k| o[k] + d[k] * contact.distance);
        match fate {
            Fate::Through => self.o = [0, 1, 2].map(|k| hit[k] + d[k] * NUDGE),
            Fate::Reflects => {
                self.d = [0, 1, 2].map(|k| d[k] - 2.0 * along * n[k]);
                self.o = [0, 1, 2].map(|k| hit[k] + n[k] * NUDGE);
            }
            Fate::Ends(_) => {}
        }
    }
}

/// What a surface does with a pulse that meets it ([`Pulses::fate`]).
#[derive(Copy, Clone, Debug, PartialEq)]
enum Fate {
    /// The pulse ends there: it comes back, or is lost.
    Ends(Echo),
    /// It goes on through the surface (a pane).
    Through,
    /// It is reflected (a mirror, metal, a pane).
    Reflects,
}

/// How far a continued pulse starts from the surface it left, metres.
const NUDGE: f64 = 1e-5;

impl Contact {
    /// The cosine of the incidence of a pulse along `d`: larger is nearer the normal (which
    /// faces the pulse).
    #[inline(always)]
    fn cos_in(&self, d: [f64; 3]) -> f64 {
        let n = self.normal;
        let along = d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
        (-along).clamp(-1.0, 1.0)
    }
}

impl From<Hit> for Contact {
    fn from(hit: Hit) -> Self {
        Contact {
            distance: hit.distance,
            normal: hit.normal,
            material: hit.material,
            face: match hit.surface {
                Surface::Face(i) => Some(i),
                _ => None,
            },
        }
    }
}

/// `best`, or the nearest of `discs` the ray meets first (their sides, between the floor and
/// their tops), within `max`.
fn nearer_disc<'d>(
    mut best: Option<Contact>,
    discs: impl Iterator<Item = &'d Disc>,
    origin: [f64; 3],
    dir: [f64; 3],
    max: f64,
) -> Option<Contact> {
    let mut discs = discs.peekable();
    if discs.peek().is_none() {
        // Nothing to meet: return before the ray's set-up for the discs (a square root and a
        // division), which the compiler would otherwise hoist above the loop.
        return best;
    }
    for disc in discs {
        let limit = best.as_ref().map_or(max, |c| c.distance);
        if let Some(c) = disc_contact(disc, origin, dir, limit) {
            best = Some(c);
        }
    }
    best
}

/// Where the ray meets `disc`'s side within `limit` metres.
#[inline]
fn disc_contact(disc: &Disc, origin: [f64; 3], dir: [f64; 3], limit: f64) -> Option<Contact> {
    // A quick miss: the disc's centre farther from the ray's line (in the plan) than its radius,
    // or behind the origin and clear of it.
    let w = [disc.center[0] - origin[0], disc.center[1] - origin[1]];
    let h2 = dir[0] * dir[0] + dir[1] * dir[1];
    let across = w[0] * dir[1] - w[1] * dir[0];
    let along = w[0] * dir[0] + w[1] * dir[1];
    let r = disc.radius * 1.001 + 1e-6;
    if across * across > r * r * h2 || (along < 0.0 && w[0] * w[0] + w[1] * w[1] > r * r) {
        return None;
    }
    let horizontal = h2.sqrt();
    if horizontal < 1e-12 {
        return None;
    }
    let ray = Ray::new(
        Vector::new(origin[0] as f32, origin[1] as f32),
        Vector::new((dir[0] / horizontal) as f32, (dir[1] / horizontal) as f32),
    );
    let at = Pose::from_translation(Vector::new(disc.center[0] as f32, disc.center[1] as f32));
    let ball = Ball::new(disc.radius as f32);
    let hit = ball.cast_ray_and_get_normal(&at, &ray, (limit * horizontal) as f32, true)?;
    let t = f64::from(hit.time_of_impact) / horizontal;
    let z = origin[2] + dir[2] * t;
    (hit.time_of_impact > 0.0 && (0.0..=disc.height).contains(&z)).then(|| Contact {
        distance: t,
        normal: [f64::from(hit.normal.x), f64::from(hit.normal.y), 0.0],
        material: Material::Matte,
        face: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::WorldDescription;

    fn map(text: &str) -> WorldMap {
        WorldMap::new(&WorldDescription::parse(text, "t.toml").unwrap())
    }

    fn echo(
        m: &WorldMap,
        optics: &Optics,
        body: Option<Disc>,
        origin: [f64; 2],
        angle_deg: f64,
        seed: u64,
    ) -> Echo {
        let a = angle_deg.to_radians();
        trace(
            m,
            optics,
            body,
            [origin[0], origin[1], 1.0],
            [a.cos(), a.sin(), 0.0],
            32.0,
            &mut crate::rng::substream(seed, 0),
        )
    }

    /// A pulse from (4, 0) meets one long wall x = 5 of `material` at `incidence` degrees.
    fn at_incidence(material: &str, incidence: f64, seed: u64) -> Echo {
        let m = map(&format!(
            "name = \"wall\"\n[start]\nx = 0\ny = 0\n[[wall]]\nmaterial = \"{material}\"\npoints = [[5, -100], [5, 100]]\n"
        ));
        echo(&m, &Optics::default(), None, [4.0, 0.0], incidence, seed)
    }

    #[test]
    fn matte_returns_until_grazing() {
        for (incidence, returns) in [
            (0.0, true),
            (80.0, true),
            (84.0, true),
            (86.0, false),
            (89.0, false),
        ] {
            let e = at_incidence("matte", incidence, 1);
            assert_eq!(matches!(e, Echo::Range(_)), returns, "{incidence}°: {e:?}");
        }
        let Echo::Range(r) = at_incidence("matte", 60.0, 1) else {
            panic!()
        };
        assert!((r - 2.0).abs() < 1e-5, "1 m / cos 60° = 2 m, got {r}");
    }

    #[test]
    fn a_mirror_reads_the_path_to_the_object_behind() {
        // A metal mirror along x = 3 facing the origin; a wall at y = 4.
        let m = map(r#"
name = "mirror"
[start]
x = 0
y = 0
[[wall]]
material = "metal"
points = [[3, -2], [3, 6]]
[[wall]]
points = [[-10, 4], [2.9, 4]]
"#);
        let o = Optics::default();
        // At 45° up-right the pulse meets the mirror at (3, 3) after 3√2 m, reflects up-left and
        // meets y = 4 after another √2 m.
        let e = echo(&m, &o, None, [0.0, 0.0], 45.0, 1);
        let Echo::Range(r) = e else { panic!("{e:?}") };
        assert!((r - 4.0 * 2f64.sqrt()).abs() < 1e-5, "{r}");
    }

    #[test]
    fn the_robot_sees_itself_in_a_mirror() {
        let m = map(r#"
name = "mirror"
[start]
x = 0
y = 0
[[wall]]
material = "metal"
points = [[2, -3], [2, 3]]
"#);
        let o = Optics {
            metal_return: 0.0, // a perfect mirror: never returns the pulse itself
            ..Optics::default()
        };
        let body = Disc {
            center: [-0.1, 0.0],
            radius: 0.25,
            height: 1.5,
        };
        // Head-on the pulse comes straight back to the laser, through the robot's own body:
        // mirror at 2 m, then back to the front of the body at 2 - 0.15 m.
        let e = echo(&m, &o, Some(body), [0.0, 0.0], 0.0, 1);
        let Echo::Range(r) = e else { panic!("{e:?}") };
        assert!((r - (2.0 + 1.85)).abs() < 1e-4, "{r}");
    }

    #[test]
    fn black_is_seen_head_on_and_lost_obliquely() {
        for seed in 0..50 {
            assert_eq!(at_incidence("black", 0.0, seed), Echo::Range(1.0));
            assert_eq!(at_incidence("black", 60.0, seed), Echo::Lost);
        }
        // Between, a fair share comes back: at 35° the chance is one half.
        let back = (0..400)
            .filter(|&s| matches!(at_incidence("black", 35.0, s), Echo::Range(_)))
            .count();
        assert!((150..250).contains(&back), "{back}/400");
    }

    #[test]
    fn glass_returns_near_normal_and_is_window_or_mirror_beyond() {
        let m = map(r#"
name = "glass"
[start]
x = 0
y = 0
[[wall]]
material = "glass"
points = [[2, -10], [2, 10]]
[[wall]]
points = [[6, -20], [6, 20]]
[[wall]]
points = [[-3, -20], [-3, 20]]
"#);
        let o = Optics::default();
        assert_eq!(echo(&m, &o, None, [0.0, 0.0], 0.0, 1), Echo::Range(2.0));
        let (mut through, mut mirrored) = (0, 0);
        for seed in 0..200 {
            let Echo::Range(r) = echo(&m, &o, None, [0.0, 0.0], 30.0, seed) else {
                panic!()
            };
            let c = 30f64.to_radians().cos();
            if (r - 6.0 / c).abs() < 1e-4 {
                through += 1; // on to x = 6
            } else if (r - (2.0 / c + 5.0 / c)).abs() < 1e-4 {
                mirrored += 1; // back to x = -3
            } else {
                panic!("{r}");
            }
        }
        assert!(
            through > 70 && mirrored > 70,
            "{through} through, {mirrored} mirrored"
        );
    }

    #[test]
    fn bounces_are_bounded() {
        // Two parallel mirrors: the pulse would bounce forever.
        let m = map(r#"
name = "hall of mirrors"
[start]
x = 0
y = 0
[[wall]]
material = "metal"
points = [[-1, -50], [-1, 50]]
[[wall]]
material = "metal"
points = [[1, -50], [1, 50]]
"#);
        let e = echo(&m, &Optics::default(), None, [0.0, 0.0], 10.0, 1);
        assert_eq!(e, Echo::Lost);
    }

    /// The answer of a level beam read off the sweep's columns (its face and distance) is the
    /// general path's answer, echo for echo and draw for draw: from random poses in the lab
    /// (matte, black, glass and metal walls), at every incidence, grazing included, on every
    /// material, whether the pulse ends on its first face or goes on.
    #[test]
    fn a_beam_read_off_the_sweep_answers_as_the_general_path() {
        use rand::SeedableRng;
        let text = std::fs::read_to_string(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../worlds/lab.toml"),
        )
        .unwrap();
        let world = WorldDescription::parse(&text, "lab.toml").unwrap();
        let m = WorldMap::new(&world);
        let pulses = Pulses::new(&m, None, 32.0);
        let (min, max) = world.bounds();
        let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(3);
        let (mut matte, mut black, mut level_faces, mut specular) = (0, 0, 0, 0);
        for k in 0..20_000u64 {
            let origin = [
                rng.random_range(min[0]..max[0]),
                rng.random_range(min[1]..max[1]),
                rng.random_range(0.1..1.2),
            ];
            let a: f64 = rng.random_range(-3.2..3.2);
            let e: f64 = if k % 2 == 0 {
                0.0
            } else {
                rng.random_range(-0.4..0.4)
            };
            let dir = [a.cos() * e.cos(), a.sin() * e.cos(), e.sin()];
            let first = m.cast(origin, dir, 32.0);
            matte += usize::from(first.is_some_and(|h| h.material == Material::Matte));
            black += usize::from(first.is_some_and(|h| h.material == Material::Black));
            let mut r1 = crate::rng::substream(9, k);
            let general =
                pulses.trace_near(origin, dir, first.as_ref(), &mut Legs::default(), &mut r1);
            if let Some(Hit {
                surface: Surface::Face(i),
                distance,
                material,
                ..
            }) = first
                && dir[2] == 0.0
            {
                let mut r2 = crate::rng::substream(9, k);
                let off =
                    pulses.off_face(origin, dir, (distance, i), &mut Legs::default(), &mut r2);
                assert_eq!(off, general, "from {origin:?} along {dir:?}");
                assert_eq!(r1.random::<u64>(), r2.random::<u64>(), "the same draws");
                level_faces += 1;
                specular += usize::from(matches!(material, Material::Glass | Material::Metal));
            }
        }
        assert!(
            level_faces > 2000,
            "{level_faces} level beams answered off their face"
        );
        assert!(matte > 5000, "{matte} beams met matte first");
        assert!(black > 1000, "{black} beams met black first");
        assert!(
            specular > 500,
            "{specular} level beams met glass or metal first"
        );
    }
}
