; constants: an action names the place 'home' without a parameter
(define (domain constants)
  (:requirements :typing :durative-actions)
  (:types place robot)
  (:constants home - place)
  (:predicates (at ?r - robot ?p - place) (charged ?r - robot))
  (:durative-action go_home
    :parameters (?r - robot ?from - place)
    :duration (= ?duration 2)
    :condition (at start (at ?r ?from))
    :effect (and (at start (not (at ?r ?from))) (at end (at ?r home))))
  (:durative-action charge
    :parameters (?r - robot)
    :duration (= ?duration 3)
    :condition (and (at start (at ?r home)) (over all (at ?r home)))
    :effect (at end (charged ?r))))
