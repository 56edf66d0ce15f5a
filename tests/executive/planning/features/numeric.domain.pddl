; numeric fluents, a duration computed from them, a duration inequality
(define (domain numeric)
  (:requirements :typing :durative-actions :numeric-fluents :duration-inequalities)
  (:types place)
  (:predicates (at ?p - place) (road ?a ?b - place) (scanned ?p - place))
  (:functions (distance ?a ?b - place) (speed) (battery))
  (:durative-action drive
    :parameters (?a ?b - place)
    :duration (= ?duration (/ (distance ?a ?b) (speed)))
    :condition (and (at start (at ?a)) (at start (road ?a ?b))
                    (at start (>= (battery) (distance ?a ?b))))
    :effect (and (at start (not (at ?a))) (at end (at ?b))
                 (at end (decrease (battery) (distance ?a ?b)))))
  (:durative-action scan
    :parameters (?p - place)
    :duration (and (>= ?duration 1) (<= ?duration 4))
    :condition (over all (at ?p))
    :effect (at end (scanned ?p))))
