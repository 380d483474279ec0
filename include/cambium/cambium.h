/* cambium: grows plants, trees above all, with real biomechanics. The umbrella header. */
#ifndef CAMBIUM_H
#define CAMBIUM_H

#include "cambium/base.h"
#include "cambium/geom.h"
#include "cambium/io.h"
#include "cambium/mech.h"
#include "cambium/bend.h"
#include "cambium/lsys.h"
#include "cambium/write.h"
#include "cambium/plot.h"
#include "cambium/turtle.h"
#include "cambium/model.h"
#include "cambium/tree.h"
#include "cambium/ober.h"
#include "cambium/measure.h"
#include "cambium/elastica.h"
#include "cambium/elastica_growth.h"
#include "cambium/chain.h"
#include "cambium/turtle_motion.h"
#include "cambium/light.h"

#endif
