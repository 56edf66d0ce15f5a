; The world the use-case robot starts in: three places on a loop.
(define (problem usecase-world) (:domain usecase)
  (:objects dock lab office - place)
  (:init
    (robot_at dock)
    (connected dock lab) (connected lab dock)
    (connected lab office) (connected office lab)
    (connected office dock) (connected dock office)
    (photographable lab) (photographable office)
    (= (travel_time dock lab) 4) (= (travel_time lab dock) 4)
    (= (travel_time lab office) 3) (= (travel_time office lab) 3)
    (= (travel_time office dock) 5) (= (travel_time dock office) 5))
  (:goal (and)))
