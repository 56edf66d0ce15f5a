; a conditional effect: loading a heavy box also makes the robot careful
(define (domain conditional)
  (:requirements :typing :durative-actions :conditional-effects)
  (:types box)
  (:predicates (open ?b - box) (heavy ?b - box) (loaded ?b - box) (careful))
  (:durative-action load
    :parameters (?b - box)
    :duration (= ?duration 2)
    :condition (at start (open ?b))
    :effect (and (at end (loaded ?b)) (when (at end (heavy ?b)) (at end (careful))))))
