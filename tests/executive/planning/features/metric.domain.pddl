; action costs: the highway is expensive, the roads cheap
(define (domain costs)
  (:requirements :typing :action-costs)
  (:types place)
  (:predicates (at ?p - place) (road ?a ?b - place) (highway ?a ?b - place))
  (:functions (total-cost))
  (:action drive
    :parameters (?a ?b - place)
    :precondition (and (at ?a) (road ?a ?b))
    :effect (and (not (at ?a)) (at ?b) (increase (total-cost) 1)))
  (:action speed
    :parameters (?a ?b - place)
    :precondition (and (at ?a) (highway ?a ?b))
    :effect (and (not (at ?a)) (at ?b) (increase (total-cost) 100))))
