(define (problem careful) (:domain conditional)
  (:objects light big - box)
  (:init (open light) (open big) (heavy big))
  (:goal (careful)))
