; timed initial literals: the door opens at 10 and closes at 30
(define (domain door)
  (:requirements :typing :durative-actions :timed-initial-literals)
  (:types room)
  (:predicates (at ?r - room) (open ?a ?b - room))
  (:durative-action pass
    :parameters (?a ?b - room)
    :duration (= ?duration 5)
    :condition (and (at start (at ?a)) (over all (open ?a ?b)))
    :effect (and (at start (not (at ?a))) (at end (at ?b)))))
