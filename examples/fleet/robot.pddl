; What one transport robot of the depot does, in its own words (no robot parameter):
; each robot's executive checks its tasks against this domain, and runs the steps the
; fleet asks of it (examples/fleet/depot.pddl) with the same tasks.
(define (domain transport_robot)
  (:requirements :strips :typing :durative-actions :numeric-fluents)
  (:types place crate)

  (:predicates
    (robot_at ?p - place)
    (road ?from ?to - place)
    (crate_at ?c - crate ?p - place)
    (holding ?c - crate)
    (hands_free))

  (:functions
    (battery_level))                  ; kept up to date by the sensing rule

  (:durative-action drive
    :parameters (?from ?to - place)
    :duration (= ?duration 5)
    :condition (and (at start (robot_at ?from)) (over all (road ?from ?to)))
    :effect (and (at start (not (robot_at ?from))) (at end (robot_at ?to))))

  (:durative-action pick
    :parameters (?c - crate ?p - place)
    :duration (= ?duration 3)
    :condition (and (over all (robot_at ?p)) (at start (crate_at ?c ?p)) (at start (hands_free)))
    :effect (and (at start (not (crate_at ?c ?p))) (at start (not (hands_free)))
                 (at end (holding ?c))))

  (:durative-action drop
    :parameters (?c - crate ?p - place)
    :duration (= ?duration 2)
    :condition (and (over all (robot_at ?p)) (at start (holding ?c)))
    :effect (and (at start (not (holding ?c))) (at end (crate_at ?c ?p)) (at end (hands_free)))))
