(define (problem charge_r1) (:domain constants)
  (:objects r1 - robot lab - place)
  (:init (at r1 lab))
  (:goal (and (charged r1) (at r1 home))))
