; negative, disjunctive, universal and existential conditions
(define (domain conditions)
  (:requirements :typing :durative-actions :negative-preconditions
                 :disjunctive-preconditions :quantified-preconditions)
  (:types room)
  (:predicates (at ?r - room) (dirty ?r - room) (lit ?r - room) (locked ?r - room)
               (clean ?r - room) (done))
  (:durative-action move
    :parameters (?a ?b - room)
    :duration (= ?duration 1)
    :condition (and (at start (at ?a)) (at start (not (locked ?b))))
    :effect (and (at start (not (at ?a))) (at end (at ?b))))
  (:durative-action sweep
    :parameters (?r - room)
    :duration (= ?duration 2)
    :condition (and (at start (at ?r)) (at start (or (dirty ?r) (lit ?r))))
    :effect (at end (clean ?r)))
  (:durative-action finish
    :parameters ()
    :duration (= ?duration 1)
    :condition (and (at start (forall (?r - room) (or (clean ?r) (locked ?r))))
                    (at start (exists (?r - room) (at ?r))))
    :effect (at end (done))))
