(define (problem tidy) (:domain conditions)
  (:objects a b c - room)
  (:init (at a) (dirty a) (lit b) (locked c))
  (:goal (and (done) (not (clean c)))))
