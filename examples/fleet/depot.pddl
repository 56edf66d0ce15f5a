; A depot served by a fleet of transport robots: each drives between places, picks up
; one crate at a time and puts it down elsewhere. Every action names the robot that
; carries it out (its parameter of type robot): `dura fleet run` runs the step on that
; robot's executive, whose robot description maps the action to a task.
(define (domain depot)
  (:requirements :strips :typing :durative-actions :numeric-fluents)
  (:types robot place crate)

  (:predicates
    (at ?r - robot ?p - place)          ; where a robot is
    (road ?from ?to - place)            ; a path between two places
    (crate_at ?c - crate ?p - place)    ; where a crate stands
    (holding ?r - robot ?c - crate)     ; a robot carries the crate
    (hands_free ?r - robot))            ; a robot carries nothing

  (:functions
    (battery ?r - robot))               ; its charge in percent, as the robot measures it

  ; Drive along a path (the robot's behavior drive_to).
  (:durative-action drive
    :parameters (?r - robot ?from ?to - place)
    :duration (= ?duration 5)
    :condition (and
      (at start (at ?r ?from))
      (over all (road ?from ?to)))
    :effect (and
      (at start (not (at ?r ?from)))
      (at end (at ?r ?to))))

  ; Pick up a crate where the robot stands (behavior pick).
  (:durative-action pick
    :parameters (?r - robot ?c - crate ?p - place)
    :duration (= ?duration 3)
    :condition (and
      (over all (at ?r ?p))
      (at start (crate_at ?c ?p))
      (at start (hands_free ?r)))
    :effect (and
      (at start (not (crate_at ?c ?p)))
      (at start (not (hands_free ?r)))
      (at end (holding ?r ?c))))

  ; Put the carried crate down where the robot stands (behavior drop).
  (:durative-action drop
    :parameters (?r - robot ?c - crate ?p - place)
    :duration (= ?duration 2)
    :condition (and
      (over all (at ?r ?p))
      (at start (holding ?r ?c)))
    :effect (and
      (at start (not (holding ?r ?c)))
      (at end (crate_at ?c ?p))
      (at end (hands_free ?r)))))
