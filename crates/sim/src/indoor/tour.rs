//! The robot's tour through a world: goals in the rooms, planned legs, laps that close the
//! loop.

use nalgebra::Point2;
use rand::Rng;
use raypath_geometry::Pose2;

use super::floorplan::{SpaceKind, World};
use super::planner;
use super::trajectory::{self, RobotConfig, Trajectory};
use crate::error::{Result, SimError};

/// The robot's tour: from the corridor through the rooms (counter-clockwise around the
/// building centre) back to the start, then the other way round, until `duration` seconds.
pub(super) fn plan_tour<R: Rng + ?Sized>(
    world: &World,
    robot: &RobotConfig,
    duration: f64,
    rng: &mut R,
) -> Result<(Trajectory, Vec<Point2<f64>>)> {
    let plan = &world.config;
    let grid = planner::ClearanceGrid::new(&world.planning_scene, plan.width_m, plan.height_m, 0.1);
    let corridor = world.spaces.first().ok_or_else(|| SimError::InvalidScene {
        reason: "the world has no corridor".into(),
    })?;
    // Start: the freest cell near the west end of the main corridor, facing east.
    let target = Point2::new(corridor.min[0] + 1.5, corridor.center().y);
    let start_cell = (0..grid.len())
        .filter(|&c| grid.clearance(c) >= robot.planning_clearance_m + 0.2)
        .min_by(|&a, &b| {
            let score = |c: usize| (grid.center(c) - target).norm() - grid.clearance(c);
            score(a).total_cmp(&score(b)).then(a.cmp(&b))
        })
        .ok_or_else(|| SimError::InvalidScene {
            reason: "no free cell for the robot to start in".into(),
        })?;
    let start = grid.center(start_cell);
    let reachable = grid.reachable(start_cell, robot.planning_clearance_m);
    let mut trajectory = Trajectory::starting_at(Pose2::new(start.x, start.y, 0.0));
    let center = Point2::new(plan.width_m / 2.0, plan.height_m / 2.0);
    let mut rooms: Vec<usize> = (0..world.spaces.len())
        .filter(|&i| world.spaces[i].kind == SpaceKind::Room)
        .collect();
    let angle = |i: usize| {
        let c = world.spaces[i].center() - center;
        // Counter-clockwise from the west end (angle π).
        (c.y.atan2(c.x) - std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
    };
    rooms.sort_by(|&a, &b| angle(a).total_cmp(&angle(b)).then(a.cmp(&b)));
    let mut goals = Vec::new();
    let mut lap = 0;
    while trajectory.duration() < duration {
        let mut order = rooms.clone();
        if lap % 2 == 1 {
            order.reverse();
        }
        let mut targets: Vec<Point2<f64>> = order
            .iter()
            .filter_map(|&room| room_goal(world, &grid, &reachable, room, rng))
            .collect();
        // Fit the lap (rooms, then back to the start) into the remaining time: drop every
        // other room until it fits, so the log closes the loop.
        let remaining = duration - trajectory.duration();
        let (lap_trajectory, lap_goals) = loop {
            let mut trial = trajectory.clone();
            let mut stops: Vec<(Point2<f64>, bool)> = targets.iter().map(|&g| (g, true)).collect();
            stops.push((start, false));
            let visited = drive_lap(&mut trial, world, &grid, robot, &stops, rng);
            if trial.duration() - trajectory.duration() <= remaining || targets.len() <= 1 {
                break (trial, visited);
            }
            targets = targets.iter().copied().step_by(2).collect();
        };
        let moved = lap_trajectory.length_m() > trajectory.length_m() + 0.1;
        trajectory = lap_trajectory;
        goals.extend(lap_goals);
        if !moved {
            // Nowhere to go: stand still for the rest of the log.
            let rest = duration - trajectory.duration();
            trajectory.dwell(rest.max(0.0) + 1.0);
        }
        lap += 1;
    }
    Ok((trajectory, goals))
}

/// Drives to each stop in turn (looking around and pausing at room goals, the stops marked
/// `true`); returns the stops reached.
fn drive_lap<R: Rng + ?Sized>(
    trajectory: &mut Trajectory,
    world: &World,
    grid: &planner::ClearanceGrid,
    robot: &RobotConfig,
    stops: &[(Point2<f64>, bool)],
    rng: &mut R,
) -> Vec<Point2<f64>> {
    let mut reached = Vec::new();
    for &(goal, is_room) in stops {
        let position = trajectory.last().position();
        let (Some(from), Some(to)) = (grid.cell(&position), grid.cell(&goal)) else {
            continue;
        };
        let Some(mut path) = grid.astar(
            from,
            to,
            robot.planning_clearance_m,
            robot.preferred_clearance_m,
        ) else {
            continue;
        };
        if let Some(first) = path.first_mut() {
            *first = position;
        }
        if let Some(last) = path.last_mut() {
            *last = goal;
        }
        let waypoints = planner::shortcut(&world.planning_scene, &path, robot.planning_clearance_m);
        trajectory.drive(&waypoints, &world.planning_scene, robot);
        reached.push(goal);
        if is_room {
            if rng.random::<f64>() < robot.look_around_probability {
                let a = trajectory::look_around_angle(rng.random(), rng.random());
                trajectory.turn(a, robot);
            }
            let span = (robot.dwell_s[1] - robot.dwell_s[0]).max(0.0);
            trajectory.dwell(robot.dwell_s[0] + rng.random::<f64>() * span);
        }
    }
    reached
}

/// A goal in `room`: the reachable cell with clearance ≥ 0.6 m (else any reachable cell) of
/// the room nearest a random point 2–3.5 m inside its corridor door.
fn room_goal<R: Rng + ?Sized>(
    world: &World,
    grid: &planner::ClearanceGrid,
    reachable: &[bool],
    room: usize,
    rng: &mut R,
) -> Option<Point2<f64>> {
    let s = world.spaces.get(room)?;
    // Near the room's door to a corridor (2–3.5 m in, from where the laser sees the room
    // when the robot looks around), else anywhere in the room.
    let door = world.doors.iter().find(|d| {
        d.spaces.contains(&room)
            && d.spaces.iter().any(|&j| {
                world
                    .spaces
                    .get(j)
                    .is_some_and(|x| x.kind == SpaceKind::Corridor)
            })
    });
    let (u, v, depth) = (
        rng.random::<f64>(),
        rng.random::<f64>(),
        rng.random_range(2.0..3.5),
    );
    let target = match door {
        Some(d) => {
            let c = Point2::new(d.center[0], d.center[1]);
            let inward = (s.center() - c).normalize();
            let inward = if d.horizontal_wall {
                nalgebra::Vector2::new(0.0, inward.y.signum())
            } else {
                nalgebra::Vector2::new(inward.x.signum(), 0.0)
            };
            let lateral = nalgebra::Vector2::new(-inward.y, inward.x) * (u - 0.5) * 2.0;
            c + inward * depth + lateral
        }
        None => Point2::new(
            s.min[0] + u * (s.max[0] - s.min[0]),
            s.min[1] + v * (s.max[1] - s.min[1]),
        ),
    };
    let inside =
        |p: &Point2<f64>| p.x > s.min[0] && p.x < s.max[0] && p.y > s.min[1] && p.y < s.max[1];
    let candidates: Vec<usize> = (0..grid.len())
        .filter(|&c| reachable.get(c).copied().unwrap_or(false) && inside(&grid.center(c)))
        .collect();
    let good: Vec<usize> = candidates
        .iter()
        .copied()
        .filter(|&c| grid.clearance(c) >= 0.6)
        .collect();
    let pool = if good.is_empty() { &candidates } else { &good };
    pool.iter()
        .copied()
        .min_by(|&a, &b| {
            (grid.center(a) - target)
                .norm()
                .total_cmp(&(grid.center(b) - target).norm())
                .then(a.cmp(&b))
        })
        .map(|c| grid.center(c))
}
