; A transport robot in a two-floor building: it drives between places on a floor,
; rides the building's lift between floors, carries one crate at a time, and
; charges at its docking station. The lift car moves on its own when called, so a
; plan can call it while the robot is still driving to it (concurrent steps).
; Each durative action is carried out by a behavior (examples/transport/robot.yaml).
(define (domain transport)
  (:requirements :strips :typing :durative-actions :negative-preconditions)
  (:types place crate)

  (:predicates
    (robot_at ?p - place)             ; where the robot is
    (road ?from ?to - place)          ; a path on one floor
    (lift_stop ?from ?to - place)     ; the lift runs between these places
    (lift_at ?p - place)              ; where the lift car waits
    (crate_at ?c - crate ?p - place)  ; where a crate stands
    (holding ?c - crate)              ; the robot carries the crate
    (hands_free)                      ; the robot carries nothing
    (docking_station ?p - place)      ; a docking station is here
    (battery_low))                    ; set by the robot base when it needs charging

  ; Drive along a path on one floor (behavior drive_to).
  (:durative-action drive
    :parameters (?from ?to - place)
    :duration (= ?duration 5)
    :condition (and
      (at start (robot_at ?from))
      (over all (road ?from ?to)))
    :effect (and
      (at start (not (robot_at ?from)))
      (at end (robot_at ?to))))

  ; Call the empty lift car to a floor (behavior call_lift): the robot need not be there.
  (:durative-action call_lift
    :parameters (?from ?to - place)
    :duration (= ?duration 4)
    :condition (and
      (at start (lift_at ?from))
      (over all (lift_stop ?from ?to)))
    :effect (and
      (at start (not (lift_at ?from)))
      (at end (lift_at ?to))))

  ; Ride the lift to the other floor (behavior ride_lift).
  (:durative-action ride_lift
    :parameters (?from ?to - place)
    :duration (= ?duration 6)
    :condition (and
      (at start (robot_at ?from))
      (at start (lift_at ?from))
      (over all (lift_stop ?from ?to)))
    :effect (and
      (at start (not (robot_at ?from)))
      (at start (not (lift_at ?from)))
      (at end (robot_at ?to))
      (at end (lift_at ?to))))

  ; Pick up a crate where the robot stands (behavior pick).
  (:durative-action pick
    :parameters (?c - crate ?p - place)
    :duration (= ?duration 3)
    :condition (and
      (over all (robot_at ?p))
      (at start (crate_at ?c ?p))
      (at start (hands_free)))
    :effect (and
      (at start (not (crate_at ?c ?p)))
      (at start (not (hands_free)))
      (at end (holding ?c))))

  ; Put the carried crate down where the robot stands (behavior drop).
  (:durative-action drop
    :parameters (?c - crate ?p - place)
    :duration (= ?duration 2)
    :condition (and
      (over all (robot_at ?p))
      (at start (holding ?c)))
    :effect (and
      (at start (not (holding ?c)))
      (at end (crate_at ?c ?p))
      (at end (hands_free))))

  ; Dock and charge (behavior dock_and_charge).
  (:durative-action charge
    :parameters (?p - place)
    :duration (= ?duration 10)
    :condition (and
      (over all (robot_at ?p))
      (at start (docking_station ?p)))
    :effect (at end (not (battery_low))))
)
