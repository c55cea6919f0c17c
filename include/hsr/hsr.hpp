// hsr: hidden-surface removal toolkit. Include this one header for the whole public API.
#pragma once
#include <hsr/bsp.hpp>
#include <hsr/builtin.hpp>
#include <hsr/camera.hpp>
#include <hsr/common.hpp>
#include <hsr/depth_format.hpp>
#include <hsr/frame.hpp>
#include <hsr/io.hpp>
#include <hsr/limits.hpp>
#include <hsr/render.hpp>
#include <hsr/scene.hpp>
#include <hsr/verify.hpp>
#include <hsr/orbit.hpp>
#include <hsr/occlusion.hpp>
#include <hsr/precision.hpp>
#include <hsr/views.hpp>
#include <hsr/svg.hpp>
