(define (problem through) (:domain door)
  (:objects hall lab - room)
  (:init (at hall) (at 10 (open hall lab)) (at 30 (not (open hall lab))))
  (:goal (at lab)))
